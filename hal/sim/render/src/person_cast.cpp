// The cast of people image mode draws. See person_cast.hpp.
#include "aerotrack/hal/sim/person_cast.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "photo_source.hpp"

namespace aerotrack::hal::sim {
namespace {

constexpr const char* kVtest = "/usr/share/doc/opencv-doc/examples/data/vtest.avi";

/// A person of vtest.avi. Keypoints: MoveNet thunder on a 3x (cubic) enlargement of the crop, mapped
/// back to the frame, checked by eye against the drawn skeleton (aerotrack detect --draw).
PersonSpriteSpec vtestPerson(const char* name, int frame, PersonView view, std::array<int, 4> crop,
                             const std::array<Eigen::Vector2d, kNumKeypoints>& keypoints) {
  PersonSpriteSpec s;
  s.name = name;
  s.image_path = kVtest;
  s.frame = frame;
  s.view = view;
  s.crop_px = crop;
  s.keypoints_px = keypoints;
  s.foreground_strokes_px.clear();
  s.background_strokes_px.clear();
  return s;
}

}  // namespace

PersonCastSpec defaultCast() {
  PersonCastSpec cast;
  cast.people.push_back(PersonSpriteSpec{});  // basketball1_standing
  cast.people.push_back(vtestPerson("vtest_glasses", 200, PersonView::kFront, {605, 262, 52, 108},
                                    {{{640.6, 277.2},
                                      {641.5, 275.1},
                                      {638.1, 275.3},
                                      {640.5, 275.2},
                                      {632.6, 275.1},
                                      {643.0, 283.9},
                                      {624.6, 286.1},
                                      {642.2, 300.2},
                                      {619.2, 301.9},
                                      {641.3, 312.6},
                                      {629.5, 310.1},
                                      {639.2, 316.8},
                                      {627.5, 317.6},
                                      {642.6, 338.7},
                                      {627.3, 337.3},
                                      {641.5, 360.9},
                                      {627.1, 359.2}}}));
  cast.people.push_back(vtestPerson("vtest_black", 200, PersonView::kFront, {700, 252, 50, 100},
                                    {{{728.7, 264.7},
                                      {730.7, 262.4},
                                      {726.4, 262.3},
                                      {731.3, 262.3},
                                      {722.5, 262.1},
                                      {734.6, 270.8},
                                      {714.7, 273.1},
                                      {737.4, 287.6},
                                      {709.4, 290.4},
                                      {741.1, 299.2},
                                      {707.7, 305.5},
                                      {730.9, 304.9},
                                      {720.2, 305.4},
                                      {725.6, 321.2},
                                      {723.8, 323.2},
                                      {716.3, 333.2},
                                      {723.7, 344.9}}}));
  cast.people.push_back(vtestPerson("vtest_blonde", 650, PersonView::kBack, {326, 370, 62, 140},
                                    {{{358.3, 386.1},
                                      {354.5, 382.1},
                                      {360.5, 382.6},
                                      {348.4, 385.3},
                                      {361.1, 385.8},
                                      {339.1, 402.4},
                                      {367.5, 403.9},
                                      {337.2, 428.0},
                                      {371.5, 429.7},
                                      {338.7, 449.6},
                                      {376.9, 449.5},
                                      {349.6, 446.3},
                                      {366.2, 446.6},
                                      {353.5, 472.8},
                                      {368.7, 471.8},
                                      {355.0, 499.5},
                                      {370.3, 503.3}}}));
  cast.people.push_back(vtestPerson("vtest_red_jacket", 550, PersonView::kBack, {164, 366, 66, 140},
                                    {{{195.9, 382.0},
                                      {192.6, 378.3},
                                      {199.3, 378.2},
                                      {188.9, 382.0},
                                      {202.4, 381.6},
                                      {178.9, 398.4},
                                      {214.7, 398.1},
                                      {173.5, 426.0},
                                      {221.7, 422.2},
                                      {176.2, 435.8},
                                      {220.6, 439.2},
                                      {189.6, 441.0},
                                      {208.6, 440.9},
                                      {192.3, 466.9},
                                      {205.7, 466.6},
                                      {207.1, 497.7},
                                      {202.6, 497.0}}}));
  cast.people.push_back(vtestPerson("vtest_grey_jacket", 50, PersonView::kBack, {668, 256, 50, 112},
                                    {{{684.8, 267.4},
                                      {684.5, 265.6},
                                      {688.0, 265.5},
                                      {686.8, 267.6},
                                      {694.2, 267.1},
                                      {684.0, 280.9},
                                      {700.7, 278.6},
                                      {681.8, 299.7},
                                      {703.2, 297.3},
                                      {682.3, 314.4},
                                      {699.9, 311.3},
                                      {687.8, 314.4},
                                      {699.3, 313.7},
                                      {683.5, 335.1},
                                      {701.5, 335.9},
                                      {679.1, 355.5},
                                      {708.9, 362.9}}}));
  return cast;
}

rt::Status validate(const PersonCastSpec& cast) {
  if (cast.people.empty()) return rt::Error{"people: the cast is empty (give at least one person)"};
  if (cast.people.size() > kMaxCastPeople)
    return rt::Error{"people: " + std::to_string(cast.people.size()) + " people, more than " +
                     std::to_string(kMaxCastPeople)};
  std::set<std::string> names;
  for (const PersonSpriteSpec& p : cast.people) {
    if (auto status = validate(p); !status) return status;
    if (!names.insert(p.name).second) return rt::Error{"people: the name " + p.name + " is given twice"};
  }
  return rt::ok();
}

rt::Expected<std::size_t> findPerson(const PersonCastSpec& cast, const std::string& name) {
  if (cast.people.empty()) return rt::Error{"people: the cast is empty"};
  if (name.empty()) return std::size_t{0};
  for (std::size_t i = 0; i < cast.people.size(); ++i) {
    if (cast.people[i].name == name) return i;
  }
  return rt::Error{"target_person: no person named " + name + " in the cast"};
}

std::size_t castPersonFor(std::size_t id, bool look_alike, std::size_t target, std::size_t cast_size) {
  if (id == 0 || look_alike || cast_size <= 1) return target;
  return (target + 1 + (id - 1) % (cast_size - 1)) % cast_size;
}

rt::Expected<PersonSprites> loadCast(const PersonCastSpec& cast) {
  if (auto status = validate(cast); !status) return status.error();
  // Decode each file once: stills directly, videos in one pass over the frames anyone needs.
  std::map<std::string, std::set<int>> frames_of;
  for (const PersonSpriteSpec& p : cast.people) frames_of[p.image_path].insert(p.frame);
  std::map<std::pair<std::string, int>, cv::Mat> photos;
  for (const auto& [path, frames] : frames_of) {
    std::vector<int> video_frames;
    for (const int f : frames) {
      if (f < 0) {
        auto still = readPhoto(path, -1);
        if (!still) return still.error();
        photos[{path, -1}] = still.value();
      } else {
        video_frames.push_back(f);
      }
    }
    if (video_frames.empty()) continue;
    auto read = readVideoFrames(path, video_frames);
    if (!read) return read.error();
    for (std::size_t i = 0; i < video_frames.size(); ++i) photos[{path, video_frames[i]}] = (*read)[i];
  }
  PersonSprites sprites;
  for (const PersonSpriteSpec& p : cast.people) {
    auto sprite = PersonSprite::fromPhoto(p, photos.at({p.image_path, p.frame}));
    if (!sprite) return sprite.error();
    sprites.push_back(std::make_shared<const PersonSprite>(std::move(sprite.value())));
  }
  return sprites;
}

}  // namespace aerotrack::hal::sim
