// A second opinion on whom the followed track holds: see swap_check.hpp.
#include "aerotrack/estimation/swap_check.hpp"

#include <cmath>
#include <utility>

#include <Eigen/Cholesky>

namespace aerotrack::estimation {

rt::Status validate(const SwapCheckParams& p) {
  if (!(p.frames >= 0 && p.frames <= 30)) return rt::Error{"swap_check.frames: must be in [0, 30]"};
  if (!(p.chi2 > 0.0 && std::isfinite(p.chi2))) return rt::Error{"swap_check.chi2: must be > 0"};
  if (!(p.horizon_s > 0.0 && p.horizon_s <= 60.0)) return rt::Error{"swap_check.horizon_s: must be in (0, 60]"};
  if (!(p.confirm_frames >= 1 && p.confirm_frames <= 100))
    return rt::Error{"swap_check.confirm_frames: must be in [1, 100]"};
  return rt::ok();
}

SwapCheckParams parseSwapCheckParams(const rt::ConfigNode& node) {
  SwapCheckParams p;
  p.frames = node.getInt("frames", 0, 30);
  p.chi2 = node.getDouble("chi2", rt::Range::greaterThan(0.0));
  p.horizon_s = node.getDouble("horizon_s", rt::Range::openClosed(0.0, 60.0));
  p.confirm_frames = node.getInt("confirm_frames", 1, 100);
  node.finish();
  return p;
}

rt::Expected<SwapCheck> SwapCheck::create(const SwapCheckParams& params, const TargetEstimatorParams& filter) {
  if (auto s = validate(params); !s) return s.error();
  auto kept = TargetEstimator::create(filter);
  if (!kept) return kept.error();
  std::vector<TargetEstimator> window;
  window.reserve(static_cast<std::size_t>(params.frames));
  for (int i = 0; i < params.frames; ++i) {
    auto f = TargetEstimator::create(filter);
    if (!f) return f.error();
    window.push_back(std::move(f.value()));
  }
  return SwapCheck(params, std::move(window), std::move(kept.value()));
}

SwapCheck::SwapCheck(const SwapCheckParams& params, std::vector<TargetEstimator> window, TargetEstimator kept)
    : params_(params),
      window_(std::move(window)),
      nu_(window_.size(), Eigen::Vector2d::Zero()),
      S_(window_.size(), Eigen::Matrix2d::Identity()),
      stamps_(window_.size(), 0),
      kept_(std::move(kept)) {}

void SwapCheck::beforeUpdate(const TargetEstimator& followed, const TargetEstimator::Innovation& innovation,
                             rt::TimeNs stamp_ns) {
  if (kept_valid_ && !active(stamp_ns)) reset();  // no evidence came in time: the track was the person's
  if (window_.empty() || kept_valid_) return;     // off, or one hypothesis at a time
  window_[next_] = followed;
  nu_[next_] = innovation.nu_m.head<2>();
  S_[next_] = innovation.S_m2.topLeftCorner<2, 2>();
  stamps_[next_] = stamp_ns;
  next_ = (next_ + 1) % window_.size();
  if (count_ < window_.size()) ++count_;
  if (count_ < window_.size()) return;
  Eigen::Vector2d nu_sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d S_sum = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < nu_.size(); ++i) {
    nu_sum += nu_[i];
    S_sum += S_[i];
  }
  const Eigen::LLT<Eigen::Matrix2d> llt(S_sum);
  if (llt.info() != Eigen::Success || !(nu_sum.dot(llt.solve(nu_sum)) > params_.chi2)) return;
  // next_ is now the oldest: the track before the window's first measurement.
  kept_ = window_[next_];
  kept_since_ns_ = stamps_[next_];
  kept_valid_ = true;
  votes_ = 0;
  count_ = 0;
}

bool SwapCheck::active(rt::TimeNs stamp_ns) const {
  return kept_valid_ && stamp_ns - kept_since_ns_ <= rt::secondsToNs(params_.horizon_s);
}

bool SwapCheck::vote(bool evidence) {
  votes_ = evidence ? votes_ + 1 : 0;
  if (votes_ < params_.confirm_frames) return false;
  reset();
  return true;
}

void SwapCheck::reset() {
  kept_valid_ = false;
  votes_ = 0;
  count_ = 0;
  next_ = 0;
}

}  // namespace aerotrack::estimation
