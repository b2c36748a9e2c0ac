// Calibration CSV and parameter YAML of the localization (see localization_io.hpp). The YAML is read
// and written by localizationFields() (the one key list, rt/field_table.hpp) through rt::ConfigNode, so
// its errors have the project's "file:line: key: message" form.
#include "aerotrack/localization/localization_io.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

#include "aerotrack/rt/config_node.hpp"
#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::localization {
namespace {

constexpr std::array<std::string_view, 5> kColumns = {"torso_px", "u_px", "x_m", "y_m", "z_m"};
constexpr std::size_t kRequiredColumns = 4;  // z_m is optional

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::optional<double> parseNumber(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::string formatNumber(double value) {
  std::array<char, 32> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  if (ec != std::errc()) return "nan";
  return std::string(buffer.data(), end);
}

rt::Status writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return rt::Error{path + ": cannot open file for writing"};
  out << text;
  out.flush();
  if (!out) return rt::Error{path + ": cannot write file"};
  return rt::ok();
}

}  // namespace

rt::Expected<std::vector<LocalizationSample>> parseSamplesCsv(const std::string& text, const std::string& source_name) {
  std::vector<LocalizationSample> samples;
  std::array<int, kColumns.size()> column_of{};  // field index of each known column, -1 if absent
  column_of.fill(-1);
  std::size_t field_count = 0;
  bool have_header = false;
  std::size_t line_number = 0;
  std::size_t start = 0;
  const std::string_view all(text);
  while (start < all.size()) {
    const std::size_t newline = all.find('\n', start);
    const std::string_view line =
        trim(all.substr(start, newline == std::string_view::npos ? std::string_view::npos : newline - start));
    start = newline == std::string_view::npos ? all.size() : newline + 1;
    ++line_number;
    if (line.empty()) continue;
    const std::string where = source_name + ":" + std::to_string(line_number) + ": ";
    const std::vector<std::string_view> fields = splitFields(line);
    if (!have_header) {
      for (std::size_t f = 0; f < fields.size(); ++f) {
        std::size_t c = 0;
        while (c < kColumns.size() && kColumns[c] != fields[f]) ++c;
        if (c == kColumns.size()) {
          return rt::Error{where + "unknown column '" + std::string(fields[f]) +
                           "' (the header is torso_px,u_px,x_m,y_m[,z_m])"};
        }
        if (column_of[c] >= 0) return rt::Error{where + "column " + std::string(fields[f]) + " appears twice"};
        column_of[c] = static_cast<int>(f);
      }
      for (std::size_t c = 0; c < kRequiredColumns; ++c) {
        if (column_of[c] < 0) return rt::Error{where + "missing column " + std::string(kColumns[c])};
      }
      field_count = fields.size();
      have_header = true;
      continue;
    }
    if (fields.size() != field_count) {
      return rt::Error{where + "expected " + std::to_string(field_count) + " fields, got " +
                       std::to_string(fields.size())};
    }
    std::array<double, kColumns.size()> values{};
    values.fill(std::numeric_limits<double>::quiet_NaN());
    for (std::size_t c = 0; c < kColumns.size(); ++c) {
      if (column_of[c] < 0) continue;
      const std::string_view field = fields[static_cast<std::size_t>(column_of[c])];
      const std::optional<double> value = parseNumber(field);
      if (!value) {
        return rt::Error{where + std::string(kColumns[c]) + ": expected a finite number, got '" + std::string(field) +
                         "'"};
      }
      values[c] = *value;
    }
    if (!(values[0] > 0.0)) {
      return rt::Error{where + "torso_px: must be > 0, got " + formatNumber(values[0])};
    }
    const LocalizationSample sample{values[0], values[1], values[2], values[3], values[4]};
    if (const std::string why = implausibleSample(sample); !why.empty()) return rt::Error{where + why};
    samples.push_back(sample);
  }
  if (!have_header) return rt::Error{source_name + ": empty file (expected the header torso_px,u_px,x_m,y_m)"};
  if (samples.empty()) return rt::Error{source_name + ": no data rows after the header"};
  return samples;
}

rt::Expected<std::vector<LocalizationSample>> readSamplesCsv(const std::string& path) {
  rt::Expected<std::string> text = rt::readBoundedFile(path, rt::limits::kMaxCalibrationCsvBytes);
  if (!text) return text.error();
  return parseSamplesCsv(*text, path);
}

std::string formatSamplesCsv(std::span<const LocalizationSample> samples) {
  bool with_z = false;
  for (const LocalizationSample& s : samples) with_z = with_z || std::isfinite(s.z_m);
  std::string text = with_z ? "torso_px,u_px,x_m,y_m,z_m\n" : "torso_px,u_px,x_m,y_m\n";
  for (const LocalizationSample& s : samples) {
    text +=
        formatNumber(s.torso_px) + "," + formatNumber(s.u_px) + "," + formatNumber(s.x_m) + "," + formatNumber(s.y_m);
    if (with_z) text += "," + formatNumber(s.z_m);
    text += "\n";
  }
  return text;
}

rt::Status writeSamplesCsv(std::span<const LocalizationSample> samples, const std::string& path) {
  return writeFile(path, formatSamplesCsv(samples));
}

std::string formatParamsYaml(const LocalizationParams& params) {
  std::string text =
      "# aerotrack localization parameters (issue 6; paper Sect. IV-B). predict(torso_px, u_px) gives p_C\n"
      "# in metres, camera frame x forward, y left, z up.\n";
  return text + localizationFields().toYaml(params) + "\n";
}

rt::Status writeParamsYaml(const LocalizationParams& params, const std::string& path) {
  if (rt::Status valid = validatePredictions(params); !valid)
    return rt::Error{path + ": not written: " + valid.error().message};
  return writeFile(path, formatParamsYaml(params));
}

namespace {

/// The fields, then what they predict (validatePredictions), the error naming the file.
rt::Expected<LocalizationParams> parseParamsRoot(rt::Expected<rt::ConfigNode> root, const std::string& source_name) {
  if (!root) return root.error();
  const rt::ConfigNode node = *root;
  auto params = rt::parseConfig<LocalizationParams>([&node] { return localizationFields().parse(node); });
  if (!params) return params;
  if (rt::Status plausible = validatePredictions(*params); !plausible)
    return rt::Error{source_name + ": " + plausible.error().message};
  return params;
}

}  // namespace

rt::Expected<LocalizationParams> parseParamsYaml(const std::string& text, const std::string& source_name) {
  return parseParamsRoot(rt::ConfigNode::fromString(text, source_name), source_name);
}

rt::Expected<LocalizationParams> readParamsYaml(const std::string& path) {
  return parseParamsRoot(rt::ConfigNode::loadFile(path), path);
}

}  // namespace aerotrack::localization
