// How far the followed person's own looks stray from the colour learnt for them: the look gate's threshold
// (TargetTaskParams::look_gate_sigmas), robust to the frames in which the person was not alone (issue 22).
//
// The gate let through whoever looked like the person as closely as their own accepted frames did: a running
// mean plus three standard deviations of those frames' colour distances. Every frame it let through widened it.
// In a crowd, frames of the person half hidden by a passer-by (blends of two people's colours, 0.15-0.32
// against the person's own 0.06) pass at the edge of the gate and raise its mean and spread; within two
// seconds the gate passes a stranger (crowd seed 17, image mode: 0.06 +- 0.03 became 0.18 +- 0.08, and a
// passer-by at 0.30 was taken). The median and the median absolute deviation of a window of the person's frames
// (the Hampel identifier: Hampel 1974; Rousseeuw and Croux 1993) move only when half the window has changed:
// a few seconds of blends do not open the gate, while a real change of the person's look (light, a turn) fills
// the window and moves it.
#pragma once

#include <array>
#include <cstddef>

namespace aerotrack::estimation {

class LookSpread {
 public:
  /// About 5 s of the paper's 13 Hz detector (2 s at 30 Hz): longer than a passer-by's blend.
  static constexpr std::size_t kWindow = 64;
  /// The scale that makes the MAD a standard deviation for normal data: 1 / Phi^-1(3/4).
  static constexpr double kMadToSigma = 1.4826;

  /// Adds one of the person's own distances (the oldest leaves a full window). Non-finite: ignored.
  void push(double distance);
  /// Distances in the window.
  std::size_t count() const { return count_; }
  /// median + sigmas * kMadToSigma * MAD of the window (0 when empty). O(1): kept up to date by push().
  double threshold(double sigmas) const { return median_ + sigmas * kMadToSigma * mad_; }
  double median() const { return median_; }
  double mad() const { return mad_; }
  void clear() { *this = LookSpread(); }

 private:
  std::array<double, kWindow> window_{};
  std::size_t next_ = 0, count_ = 0;
  double median_ = 0.0, mad_ = 0.0;
};

}  // namespace aerotrack::estimation
