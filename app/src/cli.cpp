// Command-line parsing: see cli.hpp.
#include "cli.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "commands.hpp"

namespace aerotrack::app {

std::string ParsedArgs::valueOr(const std::string& name, const std::string& fallback) const {
  const auto it = values.find(name);
  return it == values.end() ? fallback : it->second;
}

rt::Expected<std::vector<rt::ConfigOverride>> configOverrides(const ParsedArgs& args) {
  std::vector<rt::ConfigOverride> out;
  for (const std::string& text : args.listOf("set")) {
    auto o = rt::parseConfigOverride(text);
    if (!o) return o.error();
    out.push_back(*o);
  }
  return out;
}

std::vector<std::string> ParsedArgs::listOf(const std::string& name) const {
  const auto it = lists.find(name);
  return it == lists.end() ? std::vector<std::string>{} : it->second;
}

std::vector<CommandSpec> commandTable() {
  return {
      {"run",
       "the onboard executable: devices from config, real-time executor",
       "",
       {{"config", "FILE", true, "configuration YAML (backends, tasks, parameters)"},
        {"set", "KEY=VALUE", false,
         "replace a config value (repeatable; a key path as errors name it, e.g. planning.replan_hz=20)", true},
        {"print-config", "", false, "print the effective configuration and exit"},
        {"duration-s", "S", false, "stop after S seconds (default: until SIGINT/SIGTERM)"},
        {"record", "DIR", false, "record what the devices deliver and are told into a dataset in DIR"},
        {"mcap", "FILE", false, "write a flight log for Foxglove/Lichtblick (MCAP, Foxglove schemas) to FILE"},
        {"mcap-compression", "zstd|lz4|none", false, "the flight log's chunk compression (default zstd)"},
        {"live", "PORT|HOST:PORT", false,
         "serve the flight live to Foxglove/Lichtblick (WebSocket; PORT alone: loopback only)"}},
       ""},
      {"sim",
       "closed-loop run in the built-in simulator (lockstep unless --realtime)",
       "",
       {{"scenario", "NAME|FILE", true, "scenario name in config/scenarios/ or a YAML file"},
        {"seed", "N", false, "random seed (default 1)"},
        {"speed", "MPS", false, "the person's walking speed on every leg (before the seed's jitter)"},
        {"camera", "keypoints|image", false,
         "gimbal camera: simulated detector output, or rendered images for the real detector (default: the "
         "scenario's)"},
        {"out", "DIR", false, "write summary.json and topdown.png here (default out/sim-<scenario>-<seed>)"},
        {"mode", "proposed|baseline|truth_flight", false,
         "this system, Fast-Tracker 1.0 as the paper's baseline, or perception and estimation with the drone and "
         "gimbal flown from the true person (a paired measure of identity; default proposed)"},
        {"realtime", "", false, "run at 1x on the real-time executor instead of lockstep"},
        {"record", "DIR", false, "record what the devices deliver and are told into a dataset in DIR"},
        {"mcap", "FILE", false, "write a flight log for Foxglove/Lichtblick (MCAP, Foxglove schemas) to FILE"},
        {"mcap-compression", "zstd|lz4|none", false, "the flight log's chunk compression (default zstd)"},
        {"live", "PORT|HOST:PORT", false, "with --realtime: serve the flight live to Foxglove/Lichtblick (WebSocket)"},
        {"config", "FILE", false, "configuration YAML (default config/sim.yaml)"},
        {"set", "KEY=VALUE", false,
         "replace a config value (repeatable; a key path as errors name it, e.g. planning.replan_hz=20)", true}},
       ""},
      {"replay",
       "re-run the modules on a recorded dataset (lockstep unless --realtime)",
       "DIR",
       {{"compare", "", false,
         "record the replay (OUT/replayed) and compare its outputs with the recording's, record by record"},
        {"config", "FILE", false, "configuration YAML (default DIR/config.yaml, the recorded run's)"},
        {"set", "KEY=VALUE", false,
         "replace a config value (repeatable; a key path as errors name it, e.g. planning.replan_hz=20)", true},
        {"out", "DIR", false, "where --compare writes the replay's recording (default out/replay-<name>)"},
        {"record", "DIR", false, "record the replay (its inputs and outputs) into a dataset in DIR"},
        {"offset-s", "S", false, "start this far into the recording"},
        {"mode", "proposed|baseline", false, "as sim --mode: what the recorded run flew (default proposed)"},
        {"strict", "", false, "a bad row or a missing frame stops the start (default: skipped and counted)"},
        {"mcap", "FILE", false, "write a flight log for Foxglove/Lichtblick (MCAP, Foxglove schemas) to FILE"},
        {"mcap-compression", "zstd|lz4|none", false, "the flight log's chunk compression (default zstd)"},
        {"realtime", "", false, "replay at 1x on the real-time executor"}},
       ""},
      {"export-mcap",
       "turn a recording into a flight log for Foxglove/Lichtblick (MCAP, Foxglove schemas)",
       "DIR",
       {{"out", "FILE", false, "the MCAP file (default out/<DIR's name>.mcap)"},
        {"mcap-compression", "zstd|lz4|none", false, "chunk compression (default zstd)"},
        {"strict", "", false, "a bad row stops the export (default: skipped and counted)"}},
       ""},
      {"import-video",
       "turn a video with people into a recording (a gimbal-camera stream) for replay",
       "VIDEO",
       {{"out", "DIR", true, "the recording's folder"},
        {"hfov-deg", "DEG", true, "the camera's horizontal field of view (the stated pinhole model)"},
        {"fps", "N", false, "frame rate for the stamps (default: the video's)"},
        {"start-s", "S", false, "skip the video's first S seconds"},
        {"max-frames", "N", false, "import at most N frames"},
        {"format", "jpg|png", false, "frame files (default jpg)"}},
       ""},
      {"bench",
       "seeds 1..N of a scenario, or a suite's matrix, swept over config keys (--set), as local processes or Slurm "
       "job arrays; bench.json and a table, or suite.json, report.md and plots",
       "",
       {{"scenario", "NAME|FILE", false, "scenario name in config/scenarios/ or a YAML file (or --suite)"},
        {"trials", "N", false, "number of seeds (1..N; with --scenario)"},
        {"suite", "FILE", false,
         "run a suite (config/suites/*.yaml: scenarios x speeds x modes x cameras x seeds); resumable: a trial "
         "with a complete summary.json is not run again (default --out out/suite-<name>)"},
        {"speed", "MPS", false, "the person's walking speed (as sim --speed)"},
        {"camera", "keypoints|image", false, "gimbal camera mode (as sim --camera)"},
        {"mode", "proposed|baseline|truth_flight", false,
         "this system, Fast-Tracker 1.0 as the paper's baseline, or perception and estimation with the drone and "
         "gimbal flown from the true person (a paired measure of identity; default proposed)"},
        {"out", "DIR", false, "results folder (default out/bench-<scenario>)"},
        {"jobs", "J", false,
         "trials run at once (default: the number of CPUs); with --executor slurm the array's limit (default 16)"},
        {"config", "FILE", false, "configuration YAML passed to every trial"},
        {"set", "KEY=V1,V2,...", false,
         "sweep a config key over values (repeatable: every combination is a cell; sweep-KEY.png plots against it)",
         true},
        {"executor", "local|slurm|none", false,
         "run trials as local processes (default) or as Slurm job arrays (sbatch; a shared filesystem), or only "
         "write the plan (DIR/run_trial.sh INDEX) for another engine"},
        {"no-wait", "", false, "with --executor slurm: submit and return; `aerotrack bench merge DIR` later"},
        {"slurm-partition", "NAME", false, "the partition (default: the cluster's default)"},
        {"slurm-time", "MIN", false, "time limit of one trial, minutes (default 30)"},
        {"slurm-mem", "MB", false, "memory limit of one trial, MB (default 2048)"},
        {"slurm-option", "--OPT=VALUE", false, "another sbatch option, e.g. --account=x (repeatable)", true}},
       ""},
      {"bench merge",
       "merge the trials of DIR/plan.json that have finished (any engine ran them): the reports, and the missing",
       "DIR",
       {{"resubmit-missing", "", false, "submit the trials without a result to Slurm again, then wait and merge"},
        {"no-wait", "", false, "with --resubmit-missing: submit and return"}},
       ""},
      {"detect",
       "run the keypoint detector on an image or video",
       "IMAGE|VIDEO",
       {{"model", "lightning|thunder|multipose", false, "MoveNet model (default lightning)"},
        {"json", "", false, "print one JSON object per image or video frame"},
        {"draw", "OUT.png", false, "write the skeletons over the image (a video: its last frame)"}},
       ""},
      {"dataset",
       "write a localization calibration dataset (CSV) from the simulator's ground truth",
       "",
       {{"out", "FILE.csv", true, "the dataset: torso_px,u_px,x_m,y_m (camera frame: x forward, y left)"},
        {"samples", "N", false, "number of samples (default 2000)"},
        {"seed", "N", false, "random seed (default 1)"},
        {"scenario", "NAME|FILE", false, "whose person and camera (default open)"},
        {"camera", "keypoints|image", false,
         "keypoint camera model, or rendered images through the real detector (default keypoints)"}},
       ""},
      {"calibrate",
       "fit the localization regression",
       "",
       {{"data", "TRAIN.csv", true, "training data: torso_px,u_px,x_m,y_m[,z_m]"},
        {"out", "PARAMS.yaml", true, "where to write the fitted parameters"},
        {"model", "auto|paper|pinhole", false,
         "the paper's exponential regression, the pinhole model, or the better on 20 % held out (default)"},
        {"width", "PX", false, "camera image width (default 640)"},
        {"height", "PX", false, "camera image height (default 480)"},
        {"hfov-deg", "DEG", false, "camera horizontal field of view (default 87)"}},
       ""},
      {"eval-localization",
       "evaluate a fitted localization on test data",
       "",
       {{"data", "TEST.csv", true, "test data: torso_px,u_px,x_m,y_m[,z_m]"},
        {"params", "PARAMS.yaml", true, "parameters written by calibrate"},
        {"json", "", false, "print one JSON object"}},
       ""},
  };
}

rt::Expected<ParsedArgs> parseArgs(const std::vector<std::string>& args, const std::vector<CommandSpec>& table) {
  ParsedArgs out;
  for (const std::string& a : args)
    if (a == "--help" || a == "-h") out.help = true;
  if (args.empty()) {
    if (out.help) return out;
    return rt::Error{"no command given; try 'aerotrack --help'"};
  }
  if (args[0] == "--help" || args[0] == "-h") return out;
  const CommandSpec* command = nullptr;
  std::size_t first_option = 1;
  for (const CommandSpec& c : table) {
    if (c.name == args[0] && command == nullptr) command = &c;
    // A sub-command ("bench merge") is the command's first word and a second that is not an option.
    if (args.size() > 1 && c.name == args[0] + " " + args[1]) {
      command = &c;
      first_option = 2;
      break;
    }
  }
  if (command == nullptr) return rt::Error{"unknown command '" + args[0] + "'; try 'aerotrack --help'"};
  out.command = command->name;
  if (out.help) return out;

  for (std::size_t i = first_option; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a.rfind("--", 0) != 0) {
      if (command->positional.empty() || out.positional)
        return rt::Error{command->name + ": unexpected argument '" + a + "'"};
      out.positional = a;
      continue;
    }
    std::string name = a.substr(2);
    std::optional<std::string> inline_value;
    if (const auto eq = name.find('='); eq != std::string::npos) {
      inline_value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const OptionSpec* option = nullptr;
    for (const OptionSpec& o : command->options)
      if (o.name == name) option = &o;
    if (option == nullptr) return rt::Error{command->name + ": unknown option '--" + name + "'"};
    if (option->value_name.empty()) {
      if (inline_value) return rt::Error{command->name + ": option '--" + name + "' takes no value"};
      out.flags.insert(name);
      continue;
    }
    if (!inline_value) {
      if (i + 1 >= args.size())
        return rt::Error{command->name + ": option '--" + name + "' needs a value " + option->value_name};
      inline_value = args[++i];
    }
    if (option->repeatable) {
      out.lists[name].push_back(*inline_value);
      continue;
    }
    if (out.values.count(name) != 0) return rt::Error{command->name + ": option '--" + name + "' given twice"};
    out.values[name] = *inline_value;
  }
  for (const OptionSpec& o : command->options)
    if (o.required && out.values.count(o.name) == 0)
      return rt::Error{command->name + ": missing required option --" + o.name + " " + o.value_name};
  if (!command->positional.empty() && !out.positional)
    return rt::Error{command->name + ": missing argument " + command->positional};
  return out;
}

std::string usage(const std::vector<CommandSpec>& table) {
  std::ostringstream out;
  out << "aerotrack: onboard autonomy for a quadrotor that follows a person\n\n"
      << "usage: aerotrack <command> [options]    (aerotrack <command> --help for its options)\n\ncommands:\n";
  for (const CommandSpec& c : table) {
    out << "  " << c.name << std::string(c.name.size() < 20 ? 20 - c.name.size() : 1, ' ') << c.summary;
    if (!c.landed_in.empty()) out << "  [not yet available: " << c.landed_in << "]";
    out << "\n";
  }
  out << "\nexit status: 0 success, 1 bad input or failure, 2 capability not available yet, 3 replay --compare "
         "found differences\n";
  return out.str();
}

std::string usage(const CommandSpec& c) {
  std::ostringstream out;
  out << "usage: aerotrack " << c.name;
  if (!c.positional.empty()) out << " " << c.positional;
  for (const OptionSpec& o : c.options) {
    std::string text = "--" + o.name + (o.value_name.empty() ? "" : " " + o.value_name) + (o.repeatable ? "..." : "");
    out << " " << (o.required ? text : "[" + text + "]");
  }
  out << "\n  " << c.summary << "\n";
  if (!c.landed_in.empty()) out << "  not yet available: arrives with " << c.landed_in << "\n";
  for (const OptionSpec& o : c.options)
    if (!o.help.empty()) out << "  --" << o.name << ": " << o.help << "\n";
  return out.str();
}

rt::Expected<double> parseDouble(const std::string& option, const std::string& text, double min, double max) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(v))
    return rt::Error{"--" + option + ": expected a number, got '" + text + "'"};
  if (v < min || v > max) {
    std::ostringstream msg;
    msg << "--" << option << ": " << v << " is out of range [" << min << ", " << max << "]";
    return rt::Error{msg.str()};
  }
  return v;
}

rt::Expected<std::int64_t> parseInt(const std::string& option, const std::string& text, std::int64_t min,
                                    std::int64_t max) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0)
    return rt::Error{"--" + option + ": expected an integer, got '" + text + "'"};
  if (v < min || v > max)
    return rt::Error{"--" + option + ": " + std::to_string(v) + " is out of range [" + std::to_string(min) + ", " +
                     std::to_string(max) + "]"};
  return static_cast<std::int64_t>(v);
}

int failCommand(const char* command, const std::string& message) {
  std::fprintf(stderr, "aerotrack %s: %s\n", command, message.c_str());
  return 1;
}

}  // namespace aerotrack::app
