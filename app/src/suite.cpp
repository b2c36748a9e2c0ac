// Benchmark suites: see suite.hpp.
#include "suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "bench_stats.hpp"
#include "paths.hpp"

namespace aerotrack::app {

std::string badModeError(const std::string& mode) {
  const std::vector<std::string> modes = simModes();
  if (std::find(modes.begin(), modes.end(), mode) != modes.end()) return "";
  std::string expected;
  for (std::size_t i = 0; i < modes.size(); ++i)
    expected += (i == 0 ? "" : i + 1 == modes.size() ? " or " : ", ") + modes[i];
  return "--mode: expected " + expected + ", got '" + mode + "'";
}
namespace {

std::string suiteSpeedText(double speed_mps) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", speed_mps);
  return text;
}

std::string suiteScenarioTag(const std::string& scenario) {
  return std::filesystem::path(scenario).stem().string();
}

SuiteSpec parseSuiteRoot(const rt::ConfigNode& root) {
  SuiteSpec s;
  s.source = root.sourceName();
  s.name = root.getString("name");
  if (root.isList("seeds")) {
    const std::vector<double> range = root.getDoubleList("seeds", 2, 0.0, 1e9);
    if (range[0] != std::floor(range[0]) || range[1] != std::floor(range[1]) || range[1] < range[0])
      root.fail("seeds", "expected whole numbers [first, last] with first <= last");
    s.first_seed = static_cast<std::int64_t>(range[0]);
    s.last_seed = static_cast<std::int64_t>(range[1]);
  } else {
    s.first_seed = 1;
    s.last_seed = root.getInt("seeds", 1, 100000);
  }
  if (root.has("targets")) {
    const rt::ConfigNode t = root.child("targets");
    if (t.has("followed_rate")) s.targets.followed_rate = t.getDouble("followed_rate", 0.0, 1.0);
    if (t.has("success_rate")) s.targets.success_rate = t.getDouble("success_rate", 0.0, 1.0);
    if (t.has("visible_ratio")) s.targets.visible_ratio = t.getDouble("visible_ratio", 0.0, 1.0);
    t.finish();
  }
  const std::vector<rt::ConfigNode> cells = root.childList("cells");
  if (cells.empty()) root.fail("cells", "expected at least one cell");
  std::set<std::string> ids;
  for (const rt::ConfigNode& c : cells) {
    SuiteCell cell;
    cell.scenario = c.getString("scenario");
    if (cell.scenario.empty()) c.fail("scenario", "must not be empty");
    std::vector<std::optional<double>> speeds{std::nullopt};
    if (c.has("speeds")) {
      speeds.clear();
      // The range of `aerotrack sim --speed`.
      for (double v : c.getDoubleList("speeds", 0, 0.05, 20.0)) speeds.emplace_back(v);
      if (speeds.empty()) c.fail("speeds", "expected at least one speed (or leave the key out)");
    }
    const std::vector<std::string> modes = c.getEnumList("modes", simModes());
    cell.camera = c.has("camera") ? c.getEnum("camera", {"keypoints", "image"}) : "keypoints";
    cell.config = c.getStringOr("config", "");
    c.finish();
    for (const std::optional<double>& speed : speeds) {
      for (const std::string& mode : modes) {
        SuiteCell expanded = cell;
        expanded.speed_mps = speed;
        expanded.mode = mode;
        expanded.id = suiteScenarioTag(cell.scenario) + "-" + (speed ? suiteSpeedText(*speed) + "mps" : "own") + "-" +
                      mode + "-" + cell.camera;
        if (!cell.config.empty()) expanded.id += "-" + suiteScenarioTag(cell.config);
        if (!ids.insert(expanded.id).second) c.fail("scenario", "cell " + expanded.id + " appears twice");
        s.cells.push_back(expanded);
      }
    }
  }
  root.finish();
  return s;
}

bool suiteNumber(const nlohmann::json& object, const char* key, double& out) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_number()) return false;
  out = it->get<double>();
  return true;
}

/// "0.80 [0.49, 0.94]", flagged when under the target.
std::string suiteRateCell(const nlohmann::json& stats, const char* rate_key, const char* ci_key,
                          const std::optional<double>& target) {
  const double rate = stats.value(rate_key, 0.0);
  char text[96];
  std::snprintf(text, sizeof(text), "%s%d/%d = %.2f [%.2f, %.2f]", target && rate < *target ? "🔴 " : "",
                stats.value(rate_key == std::string("followed_rate") ? "followed_all_the_way" : "successes", 0),
                stats.value("completed", 0), rate, stats[ci_key][0].get<double>(), stats[ci_key][1].get<double>());
  return text;
}

/// The number with `decimals` decimals and a unit, or "-" when null.
std::string suiteNumberCell(const nlohmann::json& value, int decimals, const char* unit, double scale = 1.0) {
  if (!value.is_number()) return "-";
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f%s", decimals, scale * value.get<double>(), unit);
  return text;
}

/// The x of a cell in the plots: the speed asked, or else the person's measured top speed.
std::optional<double> suitePlotSpeed(const CellResult& r, const nlohmann::json& stats) {
  if (r.cell.speed_mps) return r.cell.speed_mps;
  double measured = 0.0;
  if (suiteNumber(stats, "person_top_speed_mps_mean", measured)) return measured;
  return std::nullopt;
}

std::string suiteSeriesName(const SuiteCell& cell) {
  std::string name = cell.mode;
  if (!cell.camera.empty() && cell.camera != "keypoints") name += "/" + cell.camera;
  if (!cell.config.empty()) name += "/" + suiteScenarioTag(cell.config);
  if (!cell.sets.empty()) name += " " + sweepPointLabel(cell.sets);
  return name;
}

}  // namespace

rt::Expected<SuiteSpec> parseSuite(const rt::Expected<rt::ConfigNode>& root) {
  if (!root) return root.error();
  return rt::parseConfig<SuiteSpec>([&] { return parseSuiteRoot(*root); });
}

rt::Expected<SuiteSpec> loadSuite(const std::string& path) {
  return parseSuite(rt::ConfigNode::loadFile(path));
}

std::string trialDir(const std::string& out_dir, const SuiteCell& cell, std::int64_t seed) {
  return out_dir + (cell.id.empty() ? "" : "/" + cell.id) + "/trial-" + std::to_string(seed);
}

void applySweep(SuiteSpec& suite, const std::vector<SweepPoint>& points) {
  std::vector<SuiteCell> cells;
  for (const SuiteCell& cell : suite.cells)
    for (const SweepPoint& point : points) {
      SuiteCell swept = cell;
      swept.sets.insert(swept.sets.end(), point.begin(), point.end());
      const std::string point_id = sweepPointId(point);
      if (!point_id.empty()) swept.id += (swept.id.empty() ? "" : "-") + point_id;
      cells.push_back(std::move(swept));
    }
  suite.cells = std::move(cells);
}

std::vector<std::string> trialArgs(const SuiteCell& cell, std::int64_t seed, const std::string& dir) {
  std::vector<std::string> args{"--scenario", cell.scenario, "--seed", std::to_string(seed),
                                "--out",      dir,           "--mode", cell.mode};
  if (!cell.camera.empty()) args.insert(args.end(), {"--camera", cell.camera});  // empty: the scenario's
  if (cell.speed_mps) {
    char speed[32];
    std::snprintf(speed, sizeof(speed), "%.17g", *cell.speed_mps);
    args.insert(args.end(), {"--speed", speed});
  }
  if (!cell.config.empty()) args.insert(args.end(), {"--config", cell.config});
  for (const std::string& a : sweepArgs(cell.sets)) args.push_back(a);
  return args;
}

nlohmann::json cellJson(const SuiteCell& cell) {
  nlohmann::json sets = nlohmann::json::object();
  for (const rt::ConfigOverride& o : cell.sets) sets[o.key] = o.value;
  return {{"id", cell.id},
          {"scenario", cell.scenario},
          {"speed_mps", cell.speed_mps ? nlohmann::json(*cell.speed_mps) : nlohmann::json(nullptr)},
          {"mode", cell.mode},
          {"camera", cell.camera},
          {"config", cell.config.empty() ? nlohmann::json(nullptr) : nlohmann::json(cell.config)},
          {"set", sets},
          {"set_order", [&] {
             nlohmann::json keys = nlohmann::json::array();
             for (const rt::ConfigOverride& o : cell.sets) keys.push_back(o.key);
             return keys;
           }()}};
}

rt::Expected<SuiteCell> cellFromJson(const nlohmann::json& json) {
  try {
    SuiteCell cell;
    cell.id = json.at("id").get<std::string>();
    cell.scenario = json.at("scenario").get<std::string>();
    if (!json.at("speed_mps").is_null()) cell.speed_mps = json.at("speed_mps").get<double>();
    cell.mode = json.at("mode").get<std::string>();
    cell.camera = json.at("camera").get<std::string>();
    if (!json.at("config").is_null()) cell.config = json.at("config").get<std::string>();
    for (const nlohmann::json& key : json.at("set_order"))
      cell.sets.push_back({key.get<std::string>(), json.at("set").at(key.get<std::string>()).get<std::string>()});
    return cell;
  } catch (const nlohmann::json::exception& e) {
    return rt::Error{std::string("a cell: ") + e.what()};
  }
}

bool trialComplete(const std::string& trial_dir) {
  std::ifstream in(trial_dir + "/summary.json");
  if (!in) return false;
  const nlohmann::json s = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  return s.is_object() && s.contains("success") && s["success"].is_boolean() && !s.value("interrupted", false);
}

std::vector<std::int64_t> remainingSeeds(const std::string& out_dir, const SuiteCell& cell, std::int64_t first_seed,
                                         std::int64_t last_seed) {
  std::vector<std::int64_t> out;
  for (std::int64_t seed = first_seed; seed <= last_seed; ++seed)
    if (!trialComplete(trialDir(out_dir, cell, seed))) out.push_back(seed);
  return out;
}

std::string cellError(const SuiteCell& cell) {
  const std::string scenario = resolveScenario(cell.scenario);
  if (!std::filesystem::exists(scenario)) return "scenario file " + scenario + " does not exist";
  if (!cell.config.empty() && !std::filesystem::exists(cell.config))
    return "config file " + cell.config + " does not exist";
  return "";
}

std::vector<CellResult> collectResults(const std::string& out_dir, const SuiteSpec& suite,
                                       const std::vector<std::string>& errors) {
  std::vector<CellResult> results;
  for (std::size_t i = 0; i < suite.cells.size(); ++i) {
    CellResult r;
    r.cell = suite.cells[i];
    r.error = i < errors.size() ? errors[i] : "";
    if (r.error.empty()) {
      for (std::int64_t seed = suite.first_seed; seed <= suite.last_seed; ++seed) {
        const std::string dir = trialDir(out_dir, r.cell, seed);
        if (!trialComplete(dir)) {
          r.missing_seeds.push_back(seed);
          continue;
        }
        std::ifstream in(dir + "/summary.json");
        r.summaries.push_back(nlohmann::json::parse(in, nullptr, false));
      }
    }
    results.push_back(std::move(r));
  }
  return results;
}

nlohmann::json suiteJson(const SuiteSpec& suite, const std::vector<CellResult>& results) {
  nlohmann::json cells = nlohmann::json::array();
  for (const CellResult& r : results) {
    nlohmann::json trials = nlohmann::json::array();
    for (const nlohmann::json& s : r.summaries)
      trials.push_back({{"seed", s.value("seed", nlohmann::json(nullptr))},
                        {"success", s.value("success", false)},
                        {"failure_reason", s.value("failure_reason", nlohmann::json(nullptr))},
                        {"followed_all_the_way", s.value("followed_all_the_way", false)},
                        {"follow_failure_reason", s.value("follow_failure_reason", nlohmann::json(nullptr))},
                        {"trace_hash", s.value("trace_hash", nlohmann::json(nullptr))}});
    nlohmann::json cell = cellJson(r.cell);
    cell.erase("set_order");
    cell["error"] = r.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.error);
    cell["missing_seeds"] = r.missing_seeds;
    cell["stats"] = aggregateSummaries(r.summaries);
    cell["trials"] = trials;
    cells.push_back(std::move(cell));
  }
  nlohmann::json out = suiteHeaderJson(suite);
  out["cells"] = cells;
  return out;
}

nlohmann::json suiteHeaderJson(const SuiteSpec& suite) {
  const auto target = [](const std::optional<double>& t) { return t ? nlohmann::json(*t) : nlohmann::json(nullptr); };
  return {{"name", suite.name},
          {"source", suite.source},
          {"seeds", {suite.first_seed, suite.last_seed}},
          {"targets",
           {{"followed_rate", target(suite.targets.followed_rate)},
            {"success_rate", target(suite.targets.success_rate)},
            {"visible_ratio", target(suite.targets.visible_ratio)}}}};
}

std::string suiteReport(const SuiteSpec& suite, const std::vector<CellResult>& results,
                        const std::vector<std::string>& plot_files) {
  std::string md = "# Suite " + suite.name + "\n\n";
  md += "From `" + suite.source + "`, seeds " + std::to_string(suite.first_seed) + ".." +
        std::to_string(suite.last_seed) + " in every cell (`aerotrack bench --suite`).\n\n";
  md +=
      "- **followed**: the paper's verdict (`followed_all_the_way`: no collision, no loss of sight longer than "
      "`success.max_loss_s`, never farther than `success.max_distance_m` for longer than that); **ours**: "
      "`success` (no collision, every loss re-acquired, final distance within the limit). `k/n = rate [lo, hi]`: "
      "over the completed trials, with the 95 % Wilson score interval.\n"
      "- visible: mean ratio of the tracked time the person was visible; distance: mean drone-person distance; "
      "clearance: the smallest over the cell's trials; no switch: trials without an identity switch / trials "
      "that reported identities; wrong: mean time on a bystander; person: measured top / mean speed (the mean "
      "over the walk, pauses included), averaged over trials.\n";
  if (suite.targets.followed_rate || suite.targets.success_rate || suite.targets.visible_ratio) {
    md += "- 🔴 marks a value under the suite's target:";
    if (suite.targets.followed_rate) md += " followed " + suiteSpeedText(*suite.targets.followed_rate);
    if (suite.targets.success_rate) md += " ours " + suiteSpeedText(*suite.targets.success_rate);
    if (suite.targets.visible_ratio) md += " visible " + suiteSpeedText(*suite.targets.visible_ratio);
    md += ".\n";
  }
  std::vector<std::string> scenarios;
  for (const CellResult& r : results)
    if (std::find(scenarios.begin(), scenarios.end(), r.cell.scenario) == scenarios.end())
      scenarios.push_back(r.cell.scenario);
  for (const std::string& scenario : scenarios) {
    md += "\n## " + scenario + "\n\n";
    md +=
        "| speed | mode | camera | followed | ours | visible | distance | clearance | no switch | wrong | person "
        "top / mean |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::string errors;
    for (const CellResult& r : results) {
      if (r.cell.scenario != scenario) continue;
      const std::string speed = r.cell.speed_mps ? suiteSpeedText(*r.cell.speed_mps) + " m/s" : "scenario's";
      std::string mode = r.cell.mode + (r.cell.config.empty() ? "" : " (" + r.cell.config + ")");
      if (!r.cell.sets.empty()) mode += ", " + sweepPointLabel(r.cell.sets);
      if (!r.error.empty()) {
        errors += "- **error** " + r.cell.id + ": " + r.error + "\n";
        continue;
      }
      if (!r.missing_seeds.empty())
        errors += "- " + r.cell.id + ": " + std::to_string(r.missing_seeds.size()) +
                  " trial(s) without a result (see their log.txt; run the suite again to retry them)\n";
      const nlohmann::json stats = aggregateSummaries(r.summaries);
      std::string visible = suiteNumberCell(stats["visible_ratio_mean"], 0, " %", 100.0);
      if (suite.targets.visible_ratio && stats["visible_ratio_mean"].is_number() &&
          stats["visible_ratio_mean"].get<double>() < *suite.targets.visible_ratio)
        visible.insert(0, "🔴 ");
      const nlohmann::json& id = stats["identity"];
      std::string no_switch = "-";
      if (id.value("trials_reported", 0) > 0) {
        no_switch = std::to_string(id.value("trials_without_switch", 0));
        no_switch += '/';
        no_switch += std::to_string(id.value("trials_reported", 0));
      }
      // One cell at a time (appends, not a chain of temporaries).
      for (const std::string& cell :
           {speed, mode, r.cell.camera.empty() ? std::string("scenario's") : r.cell.camera,
            suiteRateCell(stats, "followed_rate", "followed_ci95", suite.targets.followed_rate),
            suiteRateCell(stats, "success_rate", "success_ci95", suite.targets.success_rate), visible,
            suiteNumberCell(stats["distance_mean_m"], 2, " m"), suiteNumberCell(stats["min_clearance_m"], 2, " m"),
            no_switch, suiteNumberCell(id["time_on_wrong_person_s_mean"], 1, " s")}) {
        md += "| ";
        md += cell;
        md += ' ';
      }
      md += "| ";
      md += suiteNumberCell(stats["person_top_speed_mps_mean"], 2, "");
      md += " / ";
      md += suiteNumberCell(stats["person_mean_speed_mps_mean"], 2, " m/s");
      md += " |\n";
    }
    if (!errors.empty()) {
      md += '\n';
      md += errors;
    }
    const std::string plot = "plot-" + suiteScenarioTag(scenario) + ".png";
    if (std::find(plot_files.begin(), plot_files.end(), plot) != plot_files.end()) {
      md += "\n![";
      md += scenario;
      md += "](";
      md += plot;
      md += ")\n";
    }
  }
  return md;
}

namespace {

rt::Status writePlotImage(const cv::Mat& image, const std::string& path) {
  try {
    if (!cv::imwrite(path, image)) return rt::Error{path + ": cannot write image"};
  } catch (const cv::Exception& e) {
    return rt::Error{path + ": cannot write image: " + e.what()};
  }
  return rt::ok();
}

/// One panel of a plot: axes from the data, a series per mode.
struct PlotPanel {
  std::string title;
  double y_lo = 0.0, y_hi = 1.0;
  std::string x_label = "person speed, m/s";
  std::vector<std::string> x_names;  ///< Set: the x axis is categorical, x = 0, 1, ... named so.
  std::vector<double> x_ticks;       ///< Set: the x axis is labelled at these values (else at quarters).
};

struct PlotPoint {
  double x = 0.0, y = 0.0, lo = 0.0, hi = 0.0, y2 = std::nan("");  // y2: ours, in the success panel
};

void drawSuitePanel(cv::Mat& image, const cv::Rect& area, const PlotPanel& panel, double x_lo, double x_hi,
                    const std::map<std::string, std::vector<PlotPoint>>& series, bool band) {
  static const cv::Scalar kColours[] = {{200, 110, 30}, {30, 120, 230}, {60, 160, 60}, {160, 60, 160}, {40, 40, 200}};
  const int left = area.x + 55, right = area.x + area.width - 15, top = area.y + 30, bottom = area.y + area.height - 40;
  const auto px = [&](double x, double y) {
    const double fx = x_hi > x_lo ? (x - x_lo) / (x_hi - x_lo) : 0.5;
    const double fy = panel.y_hi > panel.y_lo ? (y - panel.y_lo) / (panel.y_hi - panel.y_lo) : 0.5;
    return cv::Point(static_cast<int>(std::lround(left + fx * (right - left))),
                     static_cast<int>(std::lround(bottom - fy * (bottom - top))));
  };
  cv::rectangle(image, cv::Point(left, top), cv::Point(right, bottom), cv::Scalar(0, 0, 0), 1);
  cv::putText(image, panel.title, cv::Point(left, area.y + 20), cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  char text[32];
  for (int i = 0; i <= 4; ++i) {
    const double y = panel.y_lo + (panel.y_hi - panel.y_lo) * i / 4.0;
    std::snprintf(text, sizeof(text), "%.2f", y);
    cv::putText(image, text, px(x_lo, y) + cv::Point(-50, 4), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
    if (!panel.x_names.empty() || !panel.x_ticks.empty()) continue;
    const double x = x_lo + (x_hi - x_lo) * i / 4.0;
    std::snprintf(text, sizeof(text), "%.3g", x);
    cv::putText(image, text, px(x, panel.y_lo) + cv::Point(-14, 16), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0),
                1, cv::LINE_AA);
  }
  for (const double x : panel.x_ticks) {
    std::snprintf(text, sizeof(text), "%.3g", x);
    cv::putText(image, text, px(x, panel.y_lo) + cv::Point(-14, 16), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0),
                1, cv::LINE_AA);
  }
  for (std::size_t i = 0; i < panel.x_names.size(); ++i)
    cv::putText(image, panel.x_names[i].substr(0, 12), px(static_cast<double>(i), panel.y_lo) + cv::Point(-14, 16),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(image, panel.x_label, cv::Point((left + right) / 2 - 60, bottom + 34), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  int k = 0;
  for (const auto& [name, points] : series) {
    const cv::Scalar colour = kColours[k % 5];
    if (band && !points.empty()) {  // the 95 % Wilson band, translucent
      std::vector<cv::Point> polygon;
      for (const PlotPoint& p : points) polygon.push_back(px(p.x, p.hi));
      for (auto it = points.rbegin(); it != points.rend(); ++it) polygon.push_back(px(it->x, it->lo));
      cv::Mat overlay = image.clone();
      cv::fillPoly(overlay, std::vector<std::vector<cv::Point>>{polygon}, colour);
      cv::addWeighted(overlay, 0.2, image, 0.8, 0.0, image);
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (i > 0)
        cv::line(image, px(points[i - 1].x, points[i - 1].y), px(points[i].x, points[i].y), colour, 2, cv::LINE_AA);
      cv::circle(image, px(points[i].x, points[i].y), 4, colour, cv::FILLED, cv::LINE_AA);
      if (band) {  // the interval as an error bar too, visible where a series has a single point
        cv::line(image, px(points[i].x, points[i].lo), px(points[i].x, points[i].hi), colour, 1, cv::LINE_AA);
        for (const double y : {points[i].lo, points[i].hi})
          cv::line(image, px(points[i].x, y) + cv::Point(-4, 0), px(points[i].x, y) + cv::Point(4, 0), colour, 1);
      }
      if (!std::isnan(points[i].y2))  // ours: hollow squares
        cv::drawMarker(image, px(points[i].x, points[i].y2), colour, cv::MARKER_SQUARE, 9, 1, cv::LINE_AA);
    }
    cv::putText(image, name, cv::Point(left + 8, top + 18 + 16 * k), cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1,
                cv::LINE_AA);
    ++k;
  }
}

}  // namespace

rt::Expected<std::vector<std::string>> writeSuitePlots(const std::string& out_dir, const SuiteSpec& suite,
                                                       const std::vector<CellResult>& results) {
  std::vector<std::string> files;
  std::vector<std::string> scenarios;
  for (const CellResult& r : results)
    if (std::find(scenarios.begin(), scenarios.end(), r.cell.scenario) == scenarios.end())
      scenarios.push_back(r.cell.scenario);
  for (const std::string& scenario : scenarios) {
    std::map<std::string, std::vector<PlotPoint>> success, visible, distance;
    double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, d_hi = 0.0;
    for (const CellResult& r : results) {
      if (r.cell.scenario != scenario || !r.error.empty() || r.summaries.empty()) continue;
      const nlohmann::json stats = aggregateSummaries(r.summaries);
      const std::optional<double> x = suitePlotSpeed(r, stats);
      if (!x) continue;
      x_lo = std::min(x_lo, *x);
      x_hi = std::max(x_hi, *x);
      const std::string name = suiteSeriesName(r.cell);
      success[name].push_back({*x, stats["followed_rate"].get<double>(), stats["followed_ci95"][0].get<double>(),
                               stats["followed_ci95"][1].get<double>(), stats["success_rate"].get<double>()});
      // Visibility and distance as distributions over the cell's trials: the median, and the band from the
      // 10th to the 90th percentile (issue 24 item 4).
      std::vector<double> v, d;
      for (const nlohmann::json& trial : r.summaries) {
        double value = 0.0;
        if (suiteNumber(trial, "visible_ratio", value)) v.push_back(value);
        if (suiteNumber(trial, "distance_mean_m", value)) d.push_back(value);
      }
      if (!v.empty()) visible[name].push_back({*x, quantileOf(v, 0.5), quantileOf(v, 0.1), quantileOf(v, 0.9)});
      if (!d.empty()) {
        distance[name].push_back({*x, quantileOf(d, 0.5), quantileOf(d, 0.1), quantileOf(d, 0.9)});
        d_hi = std::max(d_hi, quantileOf(d, 0.9));
      }
    }
    if (success.empty()) continue;
    for (auto* m : {&success, &visible, &distance})
      for (auto& [name, points] : *m)
        std::sort(points.begin(), points.end(), [](const PlotPoint& a, const PlotPoint& b) { return a.x < b.x; });
    if (x_hi <= x_lo) {  // a single speed: a unit-wide axis around it
      x_lo -= 0.5;
      x_hi += 0.5;
    }
    const int w = 480, h = 360;
    cv::Mat image(h + 30, 3 * w, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(image, suite.name + ": " + scenario, cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    drawSuitePanel(
        image, cv::Rect(0, 30, w, h),
        {"success: followed all the way (95% Wilson), ours (squares)", 0.0, 1.0, "person speed, m/s", {}, {}}, x_lo,
        x_hi, success, true);
    drawSuitePanel(image, cv::Rect(w, 30, w, h),
                   {"visible ratio per trial: median, 10-90 % of trials", 0.0, 1.0, "person speed, m/s", {}, {}}, x_lo,
                   x_hi, visible, true);
    drawSuitePanel(image, cv::Rect(2 * w, 30, w, h),
                   {"mean distance per trial, m: median, 10-90 %",
                    0.0,
                    std::max(1.0, std::ceil(d_hi)),
                    "person speed, m/s",
                    {},
                    {}},
                   x_lo, x_hi, distance, true);
    const std::string file = "plot-" + suiteScenarioTag(scenario) + ".png";
    std::string path = out_dir;
    path += '/';
    path += file;
    if (auto written = writePlotImage(image, path); !written) return written.error();
    files.push_back(file);
  }
  return files;
}

namespace {

/// The x of every value of a swept key: the number itself when all values are numbers, else the
/// value's place in the order given (names then label the axis).
std::map<std::string, double> sweepAxis(const SweepKey& key, std::vector<std::string>& names) {
  std::map<std::string, double> x;
  bool numeric = true;
  for (const std::string& v : key.values) {
    char* end = nullptr;
    const double number = std::strtod(v.c_str(), &end);
    numeric = numeric && !v.empty() && end == v.c_str() + v.size() && std::isfinite(number);
    x[v] = number;
  }
  if (numeric) return x;
  names = key.values;
  for (std::size_t i = 0; i < key.values.size(); ++i) x[key.values[i]] = static_cast<double>(i);
  return x;
}

}  // namespace

rt::Expected<std::vector<std::string>> writeSweepPlots(const std::string& out_dir, const SuiteSpec& suite,
                                                       const std::vector<SweepKey>& keys,
                                                       const std::vector<CellResult>& results) {
  std::vector<std::string> files;
  for (const SweepKey& key : keys) {
    std::vector<std::string> names;
    const std::map<std::string, double> axis = sweepAxis(key, names);
    std::map<std::string, std::vector<PlotPoint>> success, visible, distance;
    double d_hi = 0.0;
    for (const CellResult& r : results) {
      if (!r.error.empty() || r.summaries.empty()) continue;
      // The series: the cell without this key's value (scenario, speed, mode, camera, the other keys).
      SuiteCell rest = r.cell;
      std::string value;
      rest.sets.clear();
      for (const rt::ConfigOverride& o : r.cell.sets) {
        if (o.key == key.key) {
          value = o.value;
        } else {
          rest.sets.push_back(o);
        }
      }
      const auto x = axis.find(value);
      if (x == axis.end()) continue;
      std::string name = suiteScenarioTag(rest.scenario) + " " + suiteSeriesName(rest);
      if (rest.speed_mps) name += " " + suiteSpeedText(*rest.speed_mps) + " m/s";
      const nlohmann::json stats = aggregateSummaries(r.summaries);
      success[name].push_back({x->second, stats["followed_rate"].get<double>(), stats["followed_ci95"][0].get<double>(),
                               stats["followed_ci95"][1].get<double>(), stats["success_rate"].get<double>()});
      std::vector<double> v, d;
      for (const nlohmann::json& trial : r.summaries) {
        double number = 0.0;
        if (suiteNumber(trial, "visible_ratio", number)) v.push_back(number);
        if (suiteNumber(trial, "distance_mean_m", number)) d.push_back(number);
      }
      if (!v.empty()) visible[name].push_back({x->second, quantileOf(v, 0.5), quantileOf(v, 0.1), quantileOf(v, 0.9)});
      if (!d.empty()) {
        distance[name].push_back({x->second, quantileOf(d, 0.5), quantileOf(d, 0.1), quantileOf(d, 0.9)});
        d_hi = std::max(d_hi, quantileOf(d, 0.9));
      }
    }
    if (success.empty()) continue;
    double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
    for (const auto& [value, x] : axis) {
      x_lo = std::min(x_lo, x);
      x_hi = std::max(x_hi, x);
    }
    if (x_hi <= x_lo) {
      x_lo -= 0.5;
      x_hi += 0.5;
    } else if (!names.empty()) {  // room for the first and last names
      x_lo -= 0.3;
      x_hi += 0.3;
    }
    for (auto* m : {&success, &visible, &distance})
      for (auto& [name, points] : *m)
        std::sort(points.begin(), points.end(), [](const PlotPoint& a, const PlotPoint& b) { return a.x < b.x; });
    std::vector<double> ticks;
    if (names.empty() && axis.size() <= 8)
      for (const auto& [value, x] : axis) ticks.push_back(x);
    const int w = 480, h = 380;
    cv::Mat image(h + 30, 3 * w, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(image, suite.name + ": sweep of " + key.key, cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    drawSuitePanel(image, cv::Rect(0, 30, w, h),
                   {"success: followed all the way (95% Wilson), ours (squares)", 0.0, 1.0, key.key, names, ticks},
                   x_lo, x_hi, success, true);
    drawSuitePanel(image, cv::Rect(w, 30, w, h),
                   {"visible ratio per trial: median, 10-90 % of trials", 0.0, 1.0, key.key, names, ticks}, x_lo, x_hi,
                   visible, true);
    drawSuitePanel(
        image, cv::Rect(2 * w, 30, w, h),
        {"mean distance per trial, m: median, 10-90 %", 0.0, std::max(1.0, std::ceil(d_hi)), key.key, names, ticks},
        x_lo, x_hi, distance, true);
    std::string file = "sweep-";
    file += sweepPointId({{key.key, ""}});
    file.pop_back();  // the '=' of the empty value
    file += ".png";
    std::string path = out_dir;
    path += '/';
    path += file;
    if (auto written = writePlotImage(image, path); !written) return written.error();
    files.push_back(file);
  }
  return files;
}

}  // namespace aerotrack::app
