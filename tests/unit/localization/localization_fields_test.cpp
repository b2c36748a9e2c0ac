// The localization parameter file has one field table (localizationFields()) that drives reading,
// validate() and writing (issue 19 item 4). These tests walk that table through the module's public
// reader (parseParamsYaml) and writer (formatParamsYaml), for both models: written and read back gives
// the same parameters; at both ends of every field's range the reader and validate() agree (they did not:
// the reader took [-1e300, 1e300] and validate() any finite number); the written keys are exactly the
// keys read, the other model's section included (an unknown key). And the rule across fields: a
// parameter file whose predictions are not positions is refused by the reader, the writer and the fit.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "aerotrack/localization/localization_io.hpp"
#include "aerotrack/localization/localization_model.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "support/field_table_checks.hpp"

namespace aerotrack::localization {
namespace {

/// The table itself: the public reader (parseParamsYaml) adds a rule across fields, what the
/// parameters predict (validatePredictions, tested below), which moving one field alone breaks.
field_checks::FieldTableUnderTest<LocalizationParams> localization() {
  return {localizationFields(), [](const LocalizationParams& p) { return formatParamsYaml(p); },
          [](const std::string& yaml) -> rt::Expected<LocalizationParams> {
            auto root = rt::ConfigNode::fromString(yaml, "params.yaml");
            if (!root) return root.error();
            return rt::parseConfig<LocalizationParams>([&] { return localizationFields().parse(*root); });
          },
          [](const LocalizationParams& p) { return validate(p); }};
}

/// The defaults of each model, made valid where they are not (pinhole focal lengths 0).
std::vector<LocalizationParams> bases() {
  LocalizationParams paper;
  paper.model = LocalizationModel::kPaper;
  LocalizationParams pinhole;
  pinhole.model = LocalizationModel::kPinhole;
  pinhole.pinhole.fx_px = 460.0;
  pinhole.pinhole.fy_px = 455.5;
  return {paper, pinhole};
}

TEST(LocalizationFields, GivenParamsWhenWrittenAndReadBackThenEveryFieldIsTheSame) {
  for (const LocalizationParams& base : bases()) {
    SCOPED_TRACE(std::string(toString(base.model)));
    EXPECT_GT(field_checks::roundTrip(localization(), base), 10);
  }
}

TEST(LocalizationFields, GivenEachFieldAtTheEndsOfItsRangeThenReaderAndValidateAgree) {
  for (const LocalizationParams& base : bases()) {
    SCOPED_TRACE(std::string(toString(base.model)));
    int probes = 0;
    EXPECT_EQ(field_checks::rangeEnds(localization(), base, &probes),
              std::set<std::string>{});  // no rules across fields
    EXPECT_EQ(probes, 4 * (base.model == LocalizationModel::kPaper ? 13 : 12));
  }
}

TEST(LocalizationFields, GivenTheWrittenFileThenItsKeysAreExactlyTheKeysTheReaderReads) {
  // The noise keys came after files were written (issue 22 item 3): absent, they read as 0 (not measured).
  const std::vector<std::string> optional = {"noise_std_m", "noise_std_per_m"};
  const std::vector<std::string> paper = field_checks::keys(localization(), bases()[0], optional);
  EXPECT_EQ(paper.size(), 6U + 1U + 9U);
  const std::vector<std::string> pinhole = field_checks::keys(localization(), bases()[1], optional);
  EXPECT_EQ(pinhole.size(), 6U + 1U + 8U);
  // The other model's section is not read: an unknown key.
  const auto other = parseParamsYaml(formatParamsYaml(bases()[0]) + "pinhole: {fx_px: 1}\n", "params.yaml");
  ASSERT_FALSE(other);
  EXPECT_NE(other.error().message.find("pinhole: unknown key"), std::string::npos) << other.error().message;
}

TEST(LocalizationFields, GivenAFocalLengthOfZeroThenBothSidesNameIt) {
  LocalizationParams p = bases()[1];
  p.pinhole.fx_px = 0.0;
  ASSERT_FALSE(validate(p));
  EXPECT_EQ(validate(p).error().message, "pinhole.fx_px must be in (0, inf), got 0");
  const auto read = parseParamsYaml(formatParamsYaml(p), "params.yaml");
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().message, "params.yaml:12: pinhole.fx_px: 0 is out of range (0, inf)");
}

TEST(LocalizationFields, GivenTheWrittenFileThenItKeepsItsCommentsAndLayout) {
  const std::string text = formatParamsYaml(bases()[1]);
  EXPECT_EQ(text,
            "# aerotrack localization parameters (issue 6; paper Sect. IV-B). predict(torso_px, u_px) gives p_C\n"
            "# in metres, camera frame x forward, y left, z up.\n"
            "model: pinhole\n"
            "z_m: 0\n"
            "fit_samples: 0\n"
            "fit_mean_error_m: 0\n"
            "noise_std_m: 0\n"
            "noise_std_per_m: 0\n"
            "# x = fy_px torso_m / L + x_offset_m + x_inv_sq_m_px2 / L^2;\n"
            "# y = -x (u - cx_px) / fx_px (1 + y_scale_correction) + y_offset_m\n"
            "pinhole:\n"
            "  fx_px: 460\n"
            "  fy_px: 455.5\n"
            "  cx_px: 0\n"
            "  torso_m: 0\n"
            "  x_offset_m: 0\n"
            "  x_inv_sq_m_px2: 0\n"
            "  y_scale_correction: 0\n"
            "  y_offset_m: 0\n");
}

TEST(LocalizationFields, GivenParamsThatPredictInfinityThenReaderWriterAndFitRefuseThem) {
  LocalizationParams params = bases()[0];
  params.paper.l1_m = 10.0;
  params.paper.k1_per_px = -0.01;
  params.paper.l2_m = 1.0;
  params.paper.k2_per_px = -0.001;
  ASSERT_TRUE(validatePredictions(params)) << validatePredictions(params).error().message;
  ASSERT_TRUE(parseParamsYaml(formatParamsYaml(params), "ok.yaml"));
  params.paper.k1_per_px = 1000.0;  // a finite number: validate() takes it
  EXPECT_TRUE(validate(params));
  const auto read = parseParamsYaml(formatParamsYaml(params), "k1.yaml");
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().message.rfind("k1.yaml: paper model predicts (inf", 0), 0U) << read.error().message;
  const rt::Status written = writeParamsYaml(params, "/nonexistent/never.yaml");
  ASSERT_FALSE(written);
  EXPECT_NE(written.error().message.find("not written: paper model predicts (inf"), std::string::npos)
      << written.error().message;
}

}  // namespace
}  // namespace aerotrack::localization
