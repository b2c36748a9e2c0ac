// aerotrack: one binary, many commands (DESIGN.md, "The command line"). main parses the command
// line and dispatches; every failure ends in one line on stderr and a non-zero status.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include <glog/logging.h>
#include <opencv2/core/utils/logger.hpp>

#include "cli.hpp"
#include "commands.hpp"

int main(int argc, char** argv) {
  using namespace aerotrack::app;
  // OpenCV prints warnings of its own (DNN layer fallbacks, decoder complaints); the commands
  // report what matters in their own one-line messages.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  // Ceres logs through glog: a diverging residual during a fit printed a multi-line warning before
  // the command's own one-line error. The fit reports its failures itself; only fatal errors print.
  FLAGS_minloglevel = google::GLOG_FATAL;
  google::InitGoogleLogging(argv[0]);
  // FFmpeg (OpenCV's video reader) prints a line per damaged macroblock of a corrupt video
  // ("[msmpeg4 @ 0x...] Error at MB: 317"). OpenCV reads this variable when FFmpeg first starts
  // (cap_ffmpeg_impl.hpp): -8 is AV_LOG_QUIET. A value the user set is kept (for debugging).
  setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);  // NOLINT(concurrency-mt-unsafe): before any thread starts
  try {
    const std::vector<CommandSpec> table = commandTable();
    const auto args = parseArgs(std::vector<std::string>(argv + 1, argv + argc), table);
    if (!args) {
      std::fprintf(stderr, "aerotrack: %s\n", args.error().message.c_str());
      return 1;
    }
    if (args->command.empty()) {
      std::fputs(usage(table).c_str(), stdout);
      return 0;
    }
    const CommandSpec* spec = nullptr;
    for (const CommandSpec& c : table)
      if (c.name == args->command) spec = &c;
    if (args->help) {
      std::fputs(usage(*spec).c_str(), stdout);
      return 0;
    }
    if (!spec->landed_in.empty()) {
      std::fprintf(stderr, "aerotrack %s: not available yet; this capability arrives with %s\n", spec->name.c_str(),
                   spec->landed_in.c_str());
      return 2;
    }
    if (args->command == "run") return runCommand(*args);
    if (args->command == "sim") return simCommand(*args);
    if (args->command == "replay") return replayCommand(*args);
    if (args->command == "import-video") return importVideoCommand(*args);
    if (args->command == "export-mcap") return exportMcapCommand(*args);
    if (args->command == "bench") return benchCommand(*args);
    if (args->command == "bench merge") return benchMergeCommand(*args);
    if (args->command == "detect") return detectCommand(*args);
    if (args->command == "dataset") return datasetCommand(*args);
    if (args->command == "calibrate") return calibrateCommand(*args);
    if (args->command == "eval-localization") return evalLocalizationCommand(*args);
    std::fprintf(stderr, "aerotrack: command '%s' has no handler\n", args->command.c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "aerotrack: internal error: %s\n", e.what());
    return 1;
  }
}
