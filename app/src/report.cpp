// Exit reports: see report.hpp.
#include "report.hpp"

#include <cstdio>

namespace aerotrack::app {

std::string timingTable(const std::vector<TaskTiming>& timings) {
  std::string out;
  char line[200];
  std::snprintf(line, sizeof(line), "%-20s %10s %9s %7s %9s %9s %9s\n", "task", "runs", "overruns", "missed", "p50_ms",
                "p99_ms", "max_ms");
  out += line;
  for (const TaskTiming& t : timings) {
    std::snprintf(line, sizeof(line), "%-20s %10llu %9llu %7llu %9.4f %9.4f %9.4f\n", t.name.c_str(),
                  static_cast<unsigned long long>(t.timing.runs), static_cast<unsigned long long>(t.timing.overruns),
                  static_cast<unsigned long long>(t.timing.missed_deadlines), t.timing.p50_ms, t.timing.p99_ms,
                  t.timing.max_ms);
    out += line;
  }
  return out;
}

nlohmann::json timingJson(const std::vector<TaskTiming>& timings) {
  nlohmann::json out = nlohmann::json::object();
  for (const TaskTiming& t : timings) {
    out[t.name] = {
        {"runs", t.timing.runs},      {"overruns", t.timing.overruns}, {"missed_deadlines", t.timing.missed_deadlines},
        {"p50_ms", t.timing.p50_ms},  {"p99_ms", t.timing.p99_ms},     {"max_ms", t.timing.max_ms},
        {"mean_ms", t.timing.mean_ms}};
  }
  return out;
}

std::string deviceHealthReport(const hal::Devices& d, rt::TimeNs now_ns) {
  std::string out;
  const auto add = [&](const char* name, const hal::Device& device) {
    const hal::DeviceHealth h = device.health(now_ns);
    out += std::string(name) + " (" + std::string(device.backend()) + "): " + hal::toString(h.state) + " - " +
           h.detail + "\n";
  };
  add("gimbal_camera", *d.gimbal_camera);
  add("depth_camera", *d.depth_camera);
  add("gimbal", *d.gimbal);
  add("odometry", *d.odometry);
  add("vehicle_link", *d.vehicle_link);
  return out;
}

}  // namespace aerotrack::app
