// Tests of the localization files (issue 6): the calibration CSV (every bad input is one line
// naming the file, the line and the column) and the parameter YAML (strict, exact round trip).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "aerotrack/localization/localization_io.hpp"

namespace aerotrack::localization {
namespace {

std::string errorOf(const std::string& csv) {
  const auto result = parseSamplesCsv(csv, "data.csv");
  return result ? std::string("(no error)") : result.error().message;
}

TEST(SamplesCsv, GivenAValidFileThenSamplesInAnyColumnOrder) {
  const auto samples = parseSamplesCsv("u_px,torso_px,y_m,x_m\r\n320,50.5,-0.25,4\n\n+100.5,1e2,1,2.5e0\n", "a.csv");
  ASSERT_TRUE(samples) << samples.error().message;
  ASSERT_EQ(samples->size(), 2u);
  EXPECT_EQ((*samples)[0].torso_px, 50.5);
  EXPECT_EQ((*samples)[0].u_px, 320.0);
  EXPECT_EQ((*samples)[0].x_m, 4.0);
  EXPECT_EQ((*samples)[0].y_m, -0.25);
  EXPECT_TRUE(std::isnan((*samples)[0].z_m));
  EXPECT_EQ((*samples)[1].u_px, 100.5);
  EXPECT_EQ((*samples)[1].torso_px, 100.0);
  EXPECT_EQ((*samples)[1].x_m, 2.5);
}

TEST(SamplesCsv, GivenAnOptionalZColumnThenItIsRead) {
  const auto samples = parseSamplesCsv("torso_px,u_px,x_m,y_m,z_m\n50,320,4,0,-1.2\n", "a.csv");
  ASSERT_TRUE(samples);
  EXPECT_EQ((*samples)[0].z_m, -1.2);
}

TEST(SamplesCsv, GivenBadInputThenOneLineNamingFileLineAndColumn) {
  EXPECT_EQ(errorOf(""), "data.csv: empty file (expected the header torso_px,u_px,x_m,y_m)");
  EXPECT_EQ(errorOf("\n\n"), "data.csv: empty file (expected the header torso_px,u_px,x_m,y_m)");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n"), "data.csv: no data rows after the header");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m\n50,320,4\n"), "data.csv:1: missing column y_m");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m,w\n"),
            "data.csv:1: unknown column 'w' (the header is torso_px,u_px,x_m,y_m[,z_m])");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,x_m\n"), "data.csv:1: column x_m appears twice");
  EXPECT_EQ(errorOf("50,320,4,0\n"), "data.csv:1: unknown column '50' (the header is torso_px,u_px,x_m,y_m[,z_m])");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,4,0\n50,abc,4,0\n"),
            "data.csv:3: u_px: expected a finite number, got 'abc'");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,4,\n"), "data.csv:2: y_m: expected a finite number, got ''");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,nan,0\n"), "data.csv:2: x_m: expected a finite number, got 'nan'");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,4.0.1,0\n"),
            "data.csv:2: x_m: expected a finite number, got '4.0.1'");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,4\n"), "data.csv:2: expected 4 fields, got 3");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n0,320,4,0\n"), "data.csv:2: torso_px: must be > 0, got 0");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n-3.5,320,4,0\n"), "data.csv:2: torso_px: must be > 0, got -3.5");
  // Implausible values (issue 23 item 7): they fitted, and evaluated to errors of 6.6e132 m.
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,1e6,4,0\n"), "data.csv:2: u_px: must be in [-10000, 10000], got 1e+06");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,1e308,0\n"), "data.csv:2: x_m: must be in (0, 1000], got 1e+308");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n50,320,-2,0\n"), "data.csv:2: x_m: must be in (0, 1000], got -2");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m\n2e4,320,4,0\n"), "data.csv:2: torso_px: must be in (0, 10000], got 20000");
  EXPECT_EQ(errorOf("torso_px,u_px,x_m,y_m,z_m\n50,320,4,0,-5e3\n"),
            "data.csv:2: z_m: must be in [-1000, 1000], got -5000");
}

TEST(SamplesCsv, GivenAMissingFileThenAnError) {
  const auto result = readSamplesCsv("/nonexistent/train.csv");
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().message, "/nonexistent/train.csv: cannot open file: no such file or directory");
}

TEST(SamplesCsv, GivenSamplesWhenWrittenAndReadBackThenTheSameDoubles) {
  const std::vector<LocalizationSample> samples = {{50.123456789012345, 320.1, 4.000000000000001, -0.1},
                                                   {1e-3, -5.0, 999.999999999999, 1.0 / 3.0}};
  const auto path = (std::filesystem::temp_directory_path() / "aerotrack_samples_test.csv").string();
  ASSERT_TRUE(writeSamplesCsv(samples, path));
  const auto back = readSamplesCsv(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ((*back)[i].torso_px, samples[i].torso_px);
    EXPECT_EQ((*back)[i].u_px, samples[i].u_px);
    EXPECT_EQ((*back)[i].x_m, samples[i].x_m);
    EXPECT_EQ((*back)[i].y_m, samples[i].y_m);
  }
  EXPECT_EQ(formatSamplesCsv(samples).substr(0, 22), "torso_px,u_px,x_m,y_m\n");
}

LocalizationParams paperParams() {
  LocalizationParams p;
  p.model = LocalizationModel::kPaper;
  p.paper = {12.000000000000002, -0.03, 3.0, -0.004, 1.2, -0.003, -0.4, 0.0005, 1.0 / 3.0};
  p.z_m = -1.1;
  p.fit_samples = 1234;
  p.fit_mean_error_m = 0.123;
  return p;
}

LocalizationParams pinholeParams() {
  LocalizationParams p;
  p.model = LocalizationModel::kPinhole;
  p.pinhole = {460.0, 455.5, 322.25, 0.52, 0.15, -40.0, 0.04, -0.05};
  p.z_m = -0.8;
  p.fit_samples = 99;
  p.fit_mean_error_m = 0.1;
  return p;
}

TEST(ParamsYaml, GivenParamsWhenWrittenAndReadBackThenIdentical) {
  for (const LocalizationParams& params : {paperParams(), pinholeParams()}) {
    const auto path = (std::filesystem::temp_directory_path() / "aerotrack_params_test.yaml").string();
    ASSERT_TRUE(writeParamsYaml(params, path));
    const auto back = readParamsYaml(path);
    std::filesystem::remove(path);
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(back->model, params.model);
    EXPECT_EQ(back->z_m, params.z_m);
    EXPECT_EQ(back->fit_samples, params.fit_samples);
    EXPECT_EQ(back->fit_mean_error_m, params.fit_mean_error_m);
    // The same predictions, bit for bit.
    for (const double torso_px : {20.0, 77.7, 200.0}) {
      for (const double u_px : {0.0, 321.0, 639.0}) {
        EXPECT_EQ(predict(*back, torso_px, u_px), predict(params, torso_px, u_px));
      }
    }
  }
  EXPECT_EQ(parseParamsYaml(formatParamsYaml(paperParams()), "p.yaml")->paper.b_m, 1.0 / 3.0);
  EXPECT_EQ(parseParamsYaml(formatParamsYaml(pinholeParams()), "p.yaml")->pinhole.fy_px, 455.5);
}

std::string yamlError(const std::string& text) {
  const auto result = parseParamsYaml(text, "params.yaml");
  return result ? std::string("(no error)") : result.error().message;
}

TEST(ParamsYaml, GivenBadKeysThenErrorsNamingFileLineAndKey) {
  const std::string good = formatParamsYaml(paperParams());
  // A misspelt key.
  std::string text = good;
  text.insert(text.find("  b_m:"), "  b_mm: 0.3\n");
  EXPECT_NE(yamlError(text).find("params.yaml:"), std::string::npos);
  EXPECT_NE(yamlError(text).find("paper.b_mm: unknown key"), std::string::npos) << yamlError(text);
  // A missing key.
  text = good;
  const std::size_t at = text.find("  l3:");
  text.erase(at, text.find('\n', at) - at + 1);
  EXPECT_NE(yamlError(text).find("paper.l3"), std::string::npos) << yamlError(text);
  EXPECT_NE(yamlError(text).find("missing"), std::string::npos) << yamlError(text);
  // The other model's section.
  text = good + "pinhole:\n  fx_px: 1\n";
  EXPECT_NE(yamlError(text).find("pinhole: unknown key"), std::string::npos) << yamlError(text);
  // A bad model name and a non-number.
  text = good;
  text.replace(text.find("model: paper"), 12, "model: linear");
  EXPECT_NE(yamlError(text).find("model"), std::string::npos) << yamlError(text);
  text = good;
  text.replace(text.find("z_m: -1.1"), 9, "z_m: low");
  EXPECT_NE(yamlError(text).find("params.yaml:4: z_m"), std::string::npos) << yamlError(text);
  // A missing file.
  const auto missing = readParamsYaml("/nonexistent/params.yaml");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/params.yaml"), std::string::npos);
}

}  // namespace
}  // namespace aerotrack::localization
