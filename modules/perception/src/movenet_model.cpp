// Loading and running a converted MoveNet model: see movenet_model.hpp.
#include "aerotrack/perception/movenet_model.hpp"

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "aerotrack/rt/input_file.hpp"
#include "aerotrack/rt/input_limits.hpp"

namespace aerotrack::perception {

namespace {

const std::vector<std::string>& singleOutputs() {
  static const std::vector<std::string> kNames = {"heatmap", "center", "regress", "offset"};
  return kNames;
}
const std::vector<std::string>& multiOutputs() {
  static const std::vector<std::string> kNames = {"heatmap", "center", "regress", "offset", "box_scale", "box_offset"};
  return kNames;
}

template <class T>
rt::Expected<T> field(const nlohmann::json& j, const std::string& key, const std::string& where) {
  if (!j.contains(key)) return rt::Error{where + ": missing key '" + key + "'"};
  try {
    return j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    return rt::Error{where + ": key '" + key + "' has the wrong type"};
  }
}

}  // namespace

const std::vector<std::string>& knownModelNames() {
  static const std::vector<std::string> kNames = {"lightning", "thunder", "multipose"};
  return kNames;
}

rt::Expected<ModelInfo> readModelInfo(const std::string& sidecar_path, std::string name) {
  const rt::Expected<std::string> text = rt::readBoundedFile(sidecar_path, rt::limits::kMaxTextBytes);
  if (!text) return text.error();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.value());
  } catch (const nlohmann::json::exception& e) {
    return rt::Error{sidecar_path + ": not valid JSON"};
  }
  ModelInfo info;
  info.name = std::move(name);
  auto variant = field<std::string>(j, "variant", sidecar_path);
  if (!variant) return variant.error();
  if (*variant == "singlepose")
    info.kind = ModelKind::kSinglePose;
  else if (*variant == "multipose")
    info.kind = ModelKind::kMultiPose;
  else
    return rt::Error{sidecar_path + ": variant: expected singlepose or multipose, got '" + *variant + "'"};
  auto input_size = field<int>(j, "input_size", sidecar_path);
  if (!input_size) return input_size.error();
  auto heatmap_size = field<int>(j, "heatmap_size", sidecar_path);
  if (!heatmap_size) return heatmap_size.error();
  if (*input_size < 32 || *input_size > 4096 || *heatmap_size < 1 || *heatmap_size > *input_size)
    return rt::Error{sidecar_path + ": input_size/heatmap_size out of range"};
  info.input_size_px = *input_size;
  info.heatmap_size = *heatmap_size;

  auto scale = field<std::vector<float>>(j, "coord_scale", sidecar_path);
  if (!scale) return scale.error();
  if (scale->size() != 2 || !((*scale)[0] > 0.0F) || !((*scale)[1] > 0.0F))
    return rt::Error{sidecar_path + ": coord_scale: expected two positive numbers [y, x]"};
  DecodeConstants& c = info.constants;
  c.coord_scale_y = (*scale)[0];
  c.coord_scale_x = (*scale)[1];
  const auto read = [&](const char* key, float& out) -> rt::Status {
    auto v = field<float>(j, key, sidecar_path);
    if (!v) return v.error();
    out = *v;
    return rt::ok();
  };
  if (info.kind == ModelKind::kSinglePose) {
    if (auto s = read("distance_bias", c.distance_bias); !s) return s.error();
  } else {
    auto kernel = field<int>(j, "nms_kernel", sidecar_path);
    if (!kernel) return kernel.error();
    if (*kernel < 1 || *kernel % 2 == 0) return rt::Error{sidecar_path + ": nms_kernel: must be odd and >= 1"};
    c.nms_kernel = *kernel;
    for (const auto& [key, out] : {std::pair<const char*, float*>{"nms_tolerance", &c.nms_tolerance},
                                   {"sigma_scale", &c.sigma_scale},
                                   {"box_scale_min", &c.box_scale_min},
                                   {"box_half", &c.box_half},
                                   {"keypoint_threshold", &c.keypoint_threshold}})
      if (auto s = read(key, *out); !s) return s.error();
    if (!(c.sigma_scale > 0.0F)) return rt::Error{sidecar_path + ": sigma_scale: must be > 0"};
    auto max_persons = field<int>(j, "max_persons", sidecar_path);
    if (!max_persons) return max_persons.error();
    if (*max_persons != static_cast<int>(kMaxMultiPoseInstances))
      return rt::Error{sidecar_path + ": max_persons: the decoder handles exactly " +
                       std::to_string(kMaxMultiPoseInstances)};
  }
  return info;
}

rt::Status validate(const DnnOptions& options) {
  if (options.backend != "auto" && options.backend != "opencv" && options.backend != "cuda")
    return rt::Error{"backend: expected auto, opencv or cuda, got '" + options.backend + "'"};
  if (options.target != "auto" && options.target != "cpu" && options.target != "cuda" && options.target != "cuda_fp16")
    return rt::Error{"target: expected auto, cpu, cuda or cuda_fp16, got '" + options.target + "'"};
  return rt::ok();
}

bool cudaAvailable() {
  return !cv::dnn::getAvailableTargets(cv::dnn::DNN_BACKEND_CUDA).empty();
}

rt::Expected<MoveNetModel> MoveNetModel::load(const std::string& model_dir, const std::string& name,
                                              const DnnOptions& options) {
  bool known = false;
  for (const std::string& n : knownModelNames()) known = known || n == name;
  if (!known) return rt::Error{"unknown model '" + name + "' (known: lightning, thunder, multipose)"};
  if (auto s = validate(options); !s) return s.error();

  const std::string stem = model_dir + "/movenet-" + name;
  const std::string onnx_path = stem + ".onnx";
  const std::string sidecar_path = stem + ".decode.json";
  for (const std::string& path : {onnx_path, sidecar_path})
    if (!std::filesystem::is_regular_file(path))
      return rt::Error{path + ": model file missing; run scripts/setup.sh to download and convert the models"};

  MoveNetModel model;
  auto info = readModelInfo(sidecar_path, name);
  if (!info) return info.error();
  model.info_ = std::move(info.value());

  try {
    model.net_ = cv::dnn::readNetFromONNX(onnx_path);
  } catch (const cv::Exception& e) {
    return rt::Error{onnx_path + ": OpenCV cannot read the model: " + e.err};
  }
  if (model.net_.empty()) return rt::Error{onnx_path + ": OpenCV read an empty network"};

  const bool want_cuda = options.backend == "cuda" || options.target == "cuda" || options.target == "cuda_fp16" ||
                         (options.backend == "auto" && options.target == "auto" && cudaAvailable());
  if (want_cuda) {
    if (!cudaAvailable())
      return rt::Error{"dnn: CUDA requested but this OpenCV build has no CUDA backend (use backend: auto)"};
    model.net_.setPreferableBackend(cv::dnn::DNN_BACKEND_CUDA);
    model.net_.setPreferableTarget(options.target == "cuda_fp16" ? cv::dnn::DNN_TARGET_CUDA_FP16
                                                                 : cv::dnn::DNN_TARGET_CUDA);
    model.device_ = options.target == "cuda_fp16" ? "cuda/cuda_fp16" : "cuda/cuda";
  } else {
    model.net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    model.net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    model.device_ = "opencv/cpu";
  }
  model.output_names_ = model.info_.kind == ModelKind::kSinglePose ? singleOutputs() : multiOutputs();
  const std::vector<std::string> outputs = model.net_.getUnconnectedOutLayersNames();
  for (const std::string& wanted : model.output_names_) {
    bool found = false;
    for (const std::string& o : outputs) found = found || o == wanted;
    if (!found) {
      std::string message = onnx_path;
      message += ": the network has no output '";
      message += wanted;
      message += "' (convert it again)";
      return rt::Error{message};
    }
  }
  return model;
}

rt::Status MoveNetModel::run(const cv::Mat& blob) {
  const int s = info_.input_size_px;
  if (blob.dims != 4 || blob.size[0] != 1 || blob.size[1] != 3 || blob.size[2] != s || blob.size[3] != s ||
      blob.type() != CV_32F)
    return rt::Error{"input blob must be [1, 3, " + std::to_string(s) + ", " + std::to_string(s) + "] float32"};
  try {
    net_.setInput(blob);
    net_.forward(outputs_, output_names_);
  } catch (const cv::Exception& e) {
    return rt::Error{"inference failed: " + e.err};
  }
  const int expected_channels[] = {17, 1, 34, 34, 2, 2};
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    const cv::Mat& m = outputs_[i];
    if (m.dims != 4 || m.size[1] != expected_channels[i] || m.size[2] != info_.heatmap_size ||
        m.size[3] != info_.heatmap_size || m.type() != CV_32F || !m.isContinuous())
      return rt::Error{"head '" + output_names_[i] + "' has an unexpected shape"};
  }
  return rt::ok();
}

HeadView MoveNetModel::head(std::size_t i) const {
  if (i >= outputs_.size()) return {};
  const cv::Mat& m = outputs_[i];
  return {m.ptr<float>(), m.size[1], m.size[2], m.size[3]};
}

SinglePoseHeads MoveNetModel::singlePoseHeads() const {
  return {head(0), head(1), head(2), head(3)};
}

MultiPoseHeads MoveNetModel::multiPoseHeads() const {
  return {head(0), head(1), head(2), head(3), head(4), head(5)};
}

}  // namespace aerotrack::perception
