// Config paths: see paths.hpp.
#include "paths.hpp"

#include <cstdlib>
#include <filesystem>

namespace aerotrack::app {

std::string configDir() {
  if (const char* env = std::getenv("AEROTRACK_CONFIG_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path bin = exe.parent_path();
    for (const auto& candidate : {bin / "../../config", bin / "../share/aerotrack/config"})
      if (std::filesystem::is_directory(candidate, ec))
        return std::filesystem::weakly_canonical(candidate, ec).string();
  }
  return "config";
}

std::string modelDir() {
  if (const char* env = std::getenv("AEROTRACK_MODEL_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path bin = exe.parent_path();
    for (const auto& candidate : {bin / "../../models", bin / "../share/aerotrack/models"})
      if (std::filesystem::is_directory(candidate, ec))
        return std::filesystem::weakly_canonical(candidate, ec).string();
  }
  return "models";
}

std::string resolveScenario(const std::string& name_or_file) {
  const bool is_path = name_or_file.find('/') != std::string::npos ||
                       (name_or_file.size() > 5 && name_or_file.substr(name_or_file.size() - 5) == ".yaml");
  return is_path ? name_or_file : configDir() + "/scenarios/" + name_or_file + ".yaml";
}

}  // namespace aerotrack::app
