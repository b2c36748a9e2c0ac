// `aerotrack calibrate --data TRAIN.csv --out PARAMS.yaml [--model auto|paper|pinhole]` and
// `aerotrack eval-localization --data TEST.csv --params PARAMS.yaml [--json]`: fitting and
// evaluating the person-localization regression of the paper's Sect. IV-B (modules/localization)
// on `torso_px,u_px,x_m,y_m[,z_m]` data (DESIGN.md). The camera is the gimbal camera of the
// default config's scenarios (640 x 480, 87 degrees) unless --width/--height/--hfov-deg say
// otherwise; only the pinhole model uses it. --model auto (the default) fits both models on 80 %
// of the data, keeps the one with the lower mean error on the other 20 %, and refits it on all.
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include <nlohmann/json.hpp>

#include "aerotrack/hal/sim/keypoint_camera.hpp"
#include "aerotrack/localization/localization_eval.hpp"
#include "aerotrack/localization/localization_io.hpp"
#include "commands.hpp"

namespace aerotrack::app {
namespace {

int failWith(const char* command, const std::string& message) {
  std::fprintf(stderr, "aerotrack %s: %s\n", command, message.c_str());
  return 1;
}

rt::Expected<hal::CameraIntrinsics> intrinsicsFrom(const ParsedArgs& args) {
  const auto width = parseInt("width", args.valueOr("width", "640"), 16, 16384);
  if (!width) return width.error();
  const auto height = parseInt("height", args.valueOr("height", "480"), 16, 16384);
  if (!height) return height.error();
  const auto hfov = parseDouble("hfov-deg", args.valueOr("hfov-deg", "87"), 1.0, 179.0);
  if (!hfov) return hfov.error();
  return hal::sim::pinholeIntrinsics(static_cast<int>(*width), static_cast<int>(*height),
                                     *hfov * std::numbers::pi / 180.0);
}

/// Fits both models on the first 80 % of a deterministic shuffle, returns the one with the lower
/// held-out mean error (and both evaluations, for the report).
rt::Expected<localization::LocalizationModel> chooseModel(const std::vector<localization::LocalizationSample>& data,
                                                          const hal::CameraIntrinsics& intrinsics,
                                                          std::string& report) {
  std::vector<localization::LocalizationSample> train, held_out;
  for (std::size_t i = 0; i < data.size(); ++i) (i % 5 == 4 ? held_out : train).push_back(data[i]);
  if (held_out.size() < 5) return rt::Error{"--model auto needs at least 25 samples (or give --model)"};
  double best_error = std::numeric_limits<double>::infinity();
  localization::LocalizationModel best = localization::LocalizationModel::kPaper;
  for (const auto model : {localization::LocalizationModel::kPaper, localization::LocalizationModel::kPinhole}) {
    auto params = localization::fit(model, train, intrinsics);
    if (!params) {
      report += std::string(localization::toString(model)) + ": fit failed (" + params.error().message + "); ";
      continue;
    }
    auto eval = localization::evaluate(*params, held_out);
    if (!eval) return eval.error();
    char line[160];
    std::snprintf(line, sizeof(line), "%s: held-out mean %.3f m, p95 %.3f m; ", eval->model.c_str(), eval->mean_error_m,
                  eval->p95_error_m);
    report += line;
    if (eval->mean_error_m < best_error) {
      best_error = eval->mean_error_m;
      best = model;
    }
  }
  if (!std::isfinite(best_error)) return rt::Error{"neither model could be fitted: " + report};
  return best;
}

}  // namespace

int calibrateCommand(const ParsedArgs& args) {
  const char* self = "calibrate";
  const auto intrinsics = intrinsicsFrom(args);
  if (!intrinsics) return failWith(self, intrinsics.error().message);
  const auto data = localization::readSamplesCsv(args.values.at("data"));
  if (!data) return failWith(self, data.error().message);
  const std::string model_text = args.valueOr("model", "auto");
  std::string report;
  localization::LocalizationModel model = localization::LocalizationModel::kPaper;
  if (model_text == "auto") {
    const auto chosen = chooseModel(*data, *intrinsics, report);
    if (!chosen) return failWith(self, chosen.error().message);
    model = *chosen;
  } else {
    const auto parsed = localization::parseLocalizationModel(model_text);
    if (!parsed) return failWith(self, "--model: expected auto, paper or pinhole, got '" + model_text + "'");
    model = *parsed;
  }
  const auto params = localization::fit(model, *data, *intrinsics);
  if (!params) return failWith(self, params.error().message);
  const std::string out = args.values.at("out");
  if (const rt::Status s = localization::writeParamsYaml(*params, out); !s) return failWith(self, s.error().message);
  if (!report.empty()) std::printf("model selection (80/20 split): %s\n", report.c_str());
  std::printf("%s: %s model fitted on %zu samples, mean error %.3f m on them\n", out.c_str(),
              std::string(localization::toString(model)).c_str(), params->fit_samples, params->fit_mean_error_m);
  return 0;
}

int evalLocalizationCommand(const ParsedArgs& args) {
  const char* self = "eval-localization";
  const auto params = localization::readParamsYaml(args.values.at("params"));
  if (!params) return failWith(self, params.error().message);
  const auto data = localization::readSamplesCsv(args.values.at("data"));
  if (!data) return failWith(self, data.error().message);
  const auto eval = localization::evaluate(*params, *data);
  if (!eval) return failWith(self, eval.error().message);
  if (args.flags.count("json") != 0) {
    nlohmann::json bins = nlohmann::json::array();
    for (const localization::DistanceBin& b : eval->by_distance)
      bins.push_back({{"from_m", b.from_m},
                      {"to_m", b.to_m},
                      {"samples", b.samples},
                      {"mean_error_m", b.mean_error_m},
                      {"p95_error_m", b.p95_error_m},
                      {"max_error_m", b.max_error_m}});
    const nlohmann::json j = {{"model", eval->model},
                              {"samples", eval->samples},
                              {"mean_error_m", eval->mean_error_m},
                              {"median_error_m", eval->median_error_m},
                              {"p95_error_m", eval->p95_error_m},
                              {"max_error_m", eval->max_error_m},
                              {"by_distance", bins}};
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("%s model on %zu samples: horizontal error mean %.3f m, median %.3f m, p95 %.3f m, max %.3f m\n",
              eval->model.c_str(), eval->samples, eval->mean_error_m, eval->median_error_m, eval->p95_error_m,
              eval->max_error_m);
  std::printf("%-10s %8s %10s %10s %10s\n", "distance", "samples", "mean_m", "p95_m", "max_m");
  for (const localization::DistanceBin& b : eval->by_distance)
    std::printf("%3.0f-%-3.0f m %9zu %10.3f %10.3f %10.3f\n", b.from_m, b.to_m, b.samples, b.mean_error_m,
                b.p95_error_m, b.max_error_m);
  return 0;
}

}  // namespace aerotrack::app
