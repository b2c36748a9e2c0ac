// `aerotrack replay --compare`: the recorded run's outputs against the replay's, record by record
// (issue 10 item 5). For each stream that both recordings hold (what the devices delivered, what the
// actuators were told, the detections, the target estimates, the planned trajectories), the records are
// compared bit for bit, stamps included; the report gives the counts, the first difference (file,
// line, column, both values) and the largest absolute difference per stream.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "aerotrack/rt/expected.hpp"

namespace aerotrack::app {

struct StreamComparison {
  std::string file;  ///< Relative to the dataset folder.
  std::uint64_t recorded = 0;
  std::uint64_t replayed = 0;
  std::uint64_t past_end = 0;       ///< Replayed after the stream's last record of a recording cut short.
  std::uint64_t identical = 0;      ///< Records equal bit for bit, in order, stamps included.
  double max_abs_difference = 0.0;  ///< Over the values of records at the same index (stamps included).
  std::string first_difference;     ///< "" when the two streams are the same.
  bool same() const { return first_difference.empty(); }
};

/// Compares the streams both folders hold; with inputs false, only what the modules and actuators
/// produced (not what the devices delivered). recording_cut_short: the recording has no trusted end
/// (its recorder was killed, or its manifest's end_ns lies past its data), so it is complete only up
/// to the earliest of its streams' last records; the records of both sides stamped after that are
/// counted as past_end, not compared. Error: a stream that cannot be read (one line naming it).
rt::Expected<std::vector<StreamComparison>> compareDatasets(const std::string& recorded_dir,
                                                            const std::string& replayed_dir, bool inputs = true,
                                                            bool recording_cut_short = false);

/// One line per stream, for a person.
std::string formatComparison(const std::vector<StreamComparison>& comparisons);

}  // namespace aerotrack::app
