// bench.png: see bench_plot.hpp.
#include "bench_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_stats.hpp"

namespace aerotrack::app {
namespace {

/// A histogram of values over [lo, hi] in `bins` bins, with the median marked.
void drawHistogram(cv::Mat& image, const cv::Rect& area, const std::string& title, const std::vector<double>& values,
                   double lo, double hi, int bins, int decimals) {
  const int left = area.x + 50, right = area.x + area.width - 20, top = area.y + 34, bottom = area.y + area.height - 40;
  cv::putText(image, title, cv::Point(left, area.y + 20), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::rectangle(image, cv::Point(left, top), cv::Point(right, bottom), cv::Scalar(0, 0, 0), 1);
  std::vector<int> counts(static_cast<std::size_t>(bins), 0);
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    const int b = std::clamp(static_cast<int>(std::floor((v - lo) / (hi - lo) * bins)), 0, bins - 1);
    ++counts[static_cast<std::size_t>(b)];
  }
  const int most = std::max(1, *std::max_element(counts.begin(), counts.end()));
  const double bin_px = static_cast<double>(right - left) / bins;
  for (int b = 0; b < bins; ++b) {
    const int h =
        static_cast<int>(std::lround(static_cast<double>(counts[static_cast<std::size_t>(b)]) / most * (bottom - top)));
    const int x0 = left + static_cast<int>(std::lround(b * bin_px)),
              x1 = left + static_cast<int>(std::lround((b + 1) * bin_px));
    if (h > 0)
      cv::rectangle(image, cv::Point(x0 + 1, bottom - h), cv::Point(x1 - 1, bottom), cv::Scalar(200, 140, 60),
                    cv::FILLED);
  }
  char text[48];
  for (int i = 0; i <= 4; ++i) {
    std::snprintf(text, sizeof(text), "%.*f", decimals, lo + (hi - lo) * i / 4.0);
    cv::putText(image, text, cv::Point(left + (right - left) * i / 4 - 14, bottom + 16), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  std::snprintf(text, sizeof(text), "%d", most);
  cv::putText(image, text, cv::Point(left - 30, top + 10), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::putText(image, "trials", cv::Point(left - 46, (top + bottom) / 2), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const double median = quantileOf(values, 0.5);
  if (std::isfinite(median)) {
    const int x = left + static_cast<int>(std::lround((std::clamp(median, lo, hi) - lo) / (hi - lo) * (right - left)));
    cv::line(image, cv::Point(x, top), cv::Point(x, bottom), cv::Scalar(40, 40, 200), 2, cv::LINE_AA);
    std::snprintf(text, sizeof(text), "median %.2f", median);
    cv::putText(image, text, cv::Point(x > (left + right) / 2 ? x - 96 : x + 4, top + 16), cv::FONT_HERSHEY_SIMPLEX,
                0.4, cv::Scalar(40, 40, 200), 1, cv::LINE_AA);
  }
}

}  // namespace

rt::Status writeBenchPlot(const std::string& png_path, const BenchPlotData& data) {
  const int w = 480, h = 320;
  cv::Mat image(h + 60, 2 * w, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(image, data.title, cv::Point(10, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(image, data.verdict, cv::Point(10, 46), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(60, 60, 60), 1,
              cv::LINE_AA);
  drawHistogram(image, cv::Rect(0, 60, w, h), "person in sight, ratio of the run", data.visible_ratio, 0.0, 1.0, 20, 2);
  double d_hi = 1.0;
  for (const double d : data.distance_mean_m)
    if (std::isfinite(d)) d_hi = std::max(d_hi, std::ceil(d));
  drawHistogram(image, cv::Rect(w, 60, w, h), "mean distance to the person, m", data.distance_mean_m, 0.0, d_hi, 20, 2);
  try {
    if (!cv::imwrite(png_path, image)) return rt::Error{png_path + ": cannot write image"};
  } catch (const cv::Exception& e) {
    return rt::Error{png_path + ": cannot write image: " + e.what()};
  }
  return rt::ok();
}

}  // namespace aerotrack::app
