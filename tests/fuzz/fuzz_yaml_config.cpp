// The strict YAML reader every configuration goes through (rt::ConfigNode: parse, duplicate keys,
// every typed getter on every key) and the localization parameter file (field table + predictions).
#include <cstddef>
#include <cstdint>
#include <string>

#include "aerotrack/localization/localization_io.hpp"
#include "aerotrack/rt/config_node.hpp"
#include "fuzz_input.hpp"

namespace {

/// Keys of the shipped configurations (the seed corpus), so that the getters meet real sections.
constexpr const char* kKeys[] = {"name",  "tasks", "rate_hz", "vehicle", "max_speed_mps", "world",
                                 "boxes", "min_m", "path",    "p_m",     "seeds",         "cells",
                                 "a",     "b",     "model",   "paper",   "pinhole",       "estimation"};

/// Every getter on each of those keys that the map has, and the same further down: what section parsers
/// do. Keys the map lacks get one getter (the missing-key error): each error is a string and an
/// exception, and calling all of them on every absent key made a run 5-10 ms under ASan.
void readEverything(const aerotrack::rt::ConfigNode& node, int depth) {
  using aerotrack::rt::ConfigNode;
  bool probed_missing = false;
  for (const std::string key : kKeys) {
    if (!node.has(key)) {
      if (!probed_missing) (void)aerotrack::rt::parseConfig<int>([&] { return node.getInt(key, 0, 1); });
      probed_missing = true;
      continue;
    }
    (void)aerotrack::rt::parseConfig<int>([&] {
      (void)node.getDouble(key, -1e9, 1e9);
      return 0;
    });
    (void)aerotrack::rt::parseConfig<int>([&] {
      (void)node.getInt(key, -1000000, 1000000);
      return 0;
    });
    (void)aerotrack::rt::parseConfig<int>([&] {
      (void)node.getString(key);
      return 0;
    });
    (void)aerotrack::rt::parseConfig<int>([&] {
      (void)node.getDoubleList(key, 3, -1e9, 1e9);
      return 0;
    });
    if (depth < 3) {
      (void)aerotrack::rt::parseConfig<int>([&] {
        for (const ConfigNode& item : node.childList(key)) readEverything(item, depth + 1);
        return 0;
      });
      (void)aerotrack::rt::parseConfig<int>([&] {
        readEverything(node.child(key), depth + 1);
        return 0;
      });
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string yaml = aerotrack::fuzz::text(data, size);
  if (auto root = aerotrack::rt::ConfigNode::fromString(yaml, "fuzz.yaml")) readEverything(*root, 0);
  (void)aerotrack::localization::parseParamsYaml(yaml, "fuzz.yaml");
  return 0;
}
