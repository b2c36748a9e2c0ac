// A converted MoveNet model (scripts/models/convert_movenet.py) loaded into OpenCV's DNN: the ONNX
// graph up to the heads, plus its sidecar (<name>.decode.json) with the input size and the
// decoding constants. Backend and target come from config; "auto" picks CUDA when this OpenCV
// build has it and the CPU otherwise (Debian's OpenCV has no CUDA, so the drone's image must bring
// a CUDA build of OpenCV for the GPU).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <opencv2/dnn.hpp>

#include "aerotrack/perception/movenet_decode.hpp"
#include "aerotrack/rt/expected.hpp"

namespace aerotrack::perception {

enum class ModelKind : std::uint8_t { kSinglePose, kMultiPose };

/// What the sidecar says about a model.
struct ModelInfo {
  std::string name;  ///< "lightning", "thunder", "multipose".
  ModelKind kind = ModelKind::kSinglePose;
  int input_size_px = 0;  ///< S: the network input is S x S.
  int heatmap_size = 0;   ///< H = W of the heads.
  DecodeConstants constants;
};

/// Reads and checks a sidecar. Errors name the file and the key.
rt::Expected<ModelInfo> readModelInfo(const std::string& sidecar_path, std::string name);

struct DnnOptions {
  std::string backend = "auto";  ///< auto | opencv | cuda
  std::string target = "auto";   ///< auto | cpu | cuda | cuda_fp16
};
/// Checks the option values (not whether CUDA exists).
rt::Status validate(const DnnOptions& options);
/// True if this OpenCV build can run DNN on CUDA.
bool cudaAvailable();

/// The known model names, in the order the CLI lists them.
const std::vector<std::string>& knownModelNames();

class MoveNetModel {
 public:
  /// Loads <model_dir>/movenet-<name>.onnx and its sidecar. A missing file says which and how to
  /// provision it (scripts/setup.sh).
  static rt::Expected<MoveNetModel> load(const std::string& model_dir, const std::string& name,
                                         const DnnOptions& options);

  const ModelInfo& info() const { return info_; }
  /// "opencv/cpu", "cuda/cuda", ...
  const std::string& device() const { return device_; }

  /// Runs the network on a blob [1, 3, S, S] (makeInputBlob). The head views stay valid until the
  /// next run. Not thread-safe (one model per thread).
  rt::Status run(const cv::Mat& blob);
  SinglePoseHeads singlePoseHeads() const;
  MultiPoseHeads multiPoseHeads() const;

 private:
  MoveNetModel() = default;
  HeadView head(std::size_t i) const;

  ModelInfo info_;
  std::string device_;
  cv::dnn::Net net_;
  std::vector<std::string> output_names_;  ///< Heads in the order of the *Heads structs.
  std::vector<cv::Mat> outputs_;
};

}  // namespace aerotrack::perception
