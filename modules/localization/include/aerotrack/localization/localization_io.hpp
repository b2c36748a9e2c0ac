// Files of the localization calibration (issue 6, DESIGN.md "Calibration CSV"): the sample CSV
// `torso_px,u_px,x_m,y_m` (header required, columns in any order, an optional z_m column; x
// forward, y left, z up in the camera frame, metres) and the fitted parameters as YAML. Both are
// read strictly: every error names the file, and the line and the column or key, in one line
// ("train.csv:7: u_px: expected a number, got 'abc'"; "params.yaml:4: paper.l3: missing key").
#pragma once

#include <span>
#include <string>
#include <vector>

#include "aerotrack/localization/localization_model.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::localization {

/// Reads a calibration CSV. Errors: the file cannot be opened, is empty or has no data row; the
/// header lacks torso_px, u_px, x_m or y_m, repeats a column or has one not in
/// {torso_px, u_px, x_m, y_m, z_m}; a row with the wrong number of fields, a field that is not a
/// finite number, or torso_px <= 0. Blank lines are skipped; CRLF line ends are accepted.
/// Thread safety: reentrant. Allocates the samples.
rt::Expected<std::vector<LocalizationSample>> readSamplesCsv(const std::string& path);

/// The same, from text; source_name stands for the file name in messages.
rt::Expected<std::vector<LocalizationSample>> parseSamplesCsv(const std::string& text, const std::string& source_name);

/// Writes samples as CSV (header torso_px,u_px,x_m,y_m, plus z_m when any sample has one; values
/// in shortest round-trip form). Error if the file cannot be written. Allocates.
rt::Status writeSamplesCsv(std::span<const LocalizationSample> samples, const std::string& path);
/// The CSV text writeSamplesCsv writes.
std::string formatSamplesCsv(std::span<const LocalizationSample> samples);

/// Reads fitted parameters (the YAML formatParamsYaml writes). Strict: a missing, unknown or
/// non-numeric key, a section of the other model, or an invalid value (validate()) is an error
/// naming the file, line and key. Thread safety: reentrant. Allocates.
rt::Expected<LocalizationParams> readParamsYaml(const std::string& path);
/// The same from text; source_name stands for the file name in messages.
rt::Expected<LocalizationParams> parseParamsYaml(const std::string& text, const std::string& source_name);

/// Writes params as YAML (values in shortest round-trip form: reading them back gives the same
/// doubles). Error if the file cannot be written or params are invalid. Allocates.
rt::Status writeParamsYaml(const LocalizationParams& params, const std::string& path);
/// The YAML text writeParamsYaml writes.
std::string formatParamsYaml(const LocalizationParams& params);

}  // namespace aerotrack::localization
