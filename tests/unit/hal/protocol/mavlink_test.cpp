// The MAVLink v2 codec (hal/protocol/mavlink.hpp) against an independent implementation: the frames
// below were written by the npm package node-mavlink 2.3.0 (tools/mavlink/golden.js prints them);
// our encoder produces the same bytes and our parser reads them back. The CRC is MCRF4XX's (check
// value 0x6F91); truncated payloads are padded back; bad CRCs, unknown messages, MAVLink 1 and signed
// frames, half frames and noise are counted or waited for, never returned and never a crash.
#include "aerotrack/hal/protocol/mavlink.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace aerotrack::hal::protocol::mavlink {
namespace {

std::vector<std::uint8_t> hex(const std::string& text) {
  std::vector<std::uint8_t> out;
  for (std::size_t i = 0; i + 1 < text.size(); i += 2)
    out.push_back(static_cast<std::uint8_t>(std::stoi(text.substr(i, 2), nullptr, 16)));
  return out;
}

// node-mavlink 2.3.0, MavLinkProtocolV2(system 1, component 191).
const std::string kHeartbeatHex = "fd0900000001bf000000000000001208000403aec6";
const std::string kSetPositionTargetHex =
    "fd3500000701bf54000040e201000000c03f000010c00000e0bf0000003f000080be0000003e0000803d000000bf000000000000a03f0000c0"
    "be00000101016059";
const std::string kLocalPositionHex =
    "fd1c0000c801bf200000e80300000000604000008840000000c00000003f00000000000080be4e75";
const std::string kAttitudeHex = "fd1c0000ff01bf1e0000d00700000000003e000080bd000020400ad7233c0ad7a3bc0000003f07bd";

TEST(Mavlink, CrcIsMcrf4xx) {
  const std::string check = "123456789";
  EXPECT_EQ(crc16(reinterpret_cast<const std::uint8_t*>(check.data()), check.size()), 0x6F91);  // NOLINT
}

TEST(Mavlink, OurFramesAreNodeMavlinksFrames) {
  const Sender us{1, 191};
  Heartbeat hb;
  hb.type = 18;      // MAV_TYPE_ONBOARD_CONTROLLER
  hb.autopilot = 8;  // MAV_AUTOPILOT_INVALID
  hb.system_status = 4;
  EXPECT_EQ(frame(kHeartbeat, encodePayload(hb), us, 0), hex(kHeartbeatHex)) << "heartbeat";

  SetPositionTargetLocalNed sp;
  sp.time_boot_ms = 123456;
  sp.x = 1.5F, sp.y = -2.25F, sp.z = -1.75F;
  sp.vx = 0.5F, sp.vy = -0.25F, sp.vz = 0.125F;
  sp.afx = 0.0625F, sp.afy = -0.5F, sp.afz = 0.0F;
  sp.yaw = 1.25F, sp.yaw_rate = -0.375F;
  EXPECT_EQ(frame(kSetPositionTargetLocalNed, encodePayload(sp), us, 7), hex(kSetPositionTargetHex));

  LocalPositionNed lp;
  lp.time_boot_ms = 1000;
  lp.x = 3.5F, lp.y = 4.25F, lp.z = -2.0F, lp.vx = 0.5F, lp.vy = 0.0F, lp.vz = -0.25F;
  EXPECT_EQ(frame(kLocalPositionNed, encodePayload(lp), us, 200), hex(kLocalPositionHex));

  Attitude at;
  at.time_boot_ms = 2000;
  at.roll = 0.125F, at.pitch = -0.0625F, at.yaw = 2.5F, at.rollspeed = 0.01F, at.pitchspeed = -0.02F,
  at.yawspeed = 0.5F;
  EXPECT_EQ(frame(kAttitude, encodePayload(at), us, 255), hex(kAttitudeHex));
}

TEST(Mavlink, TheParserReadsNodeMavlinksFramesThroughNoiseAndSplits) {
  std::vector<std::uint8_t> stream = {0x00, 0x42, 0xFE, 0x17};  // noise (a MAVLink 1 start among it)
  for (const std::string* f : {&kHeartbeatHex, &kSetPositionTargetHex, &kLocalPositionHex, &kAttitudeHex}) {
    const auto bytes = hex(*f);
    stream.insert(stream.end(), bytes.begin(), bytes.end());
  }
  Parser parser;
  std::vector<Frame> frames;
  for (std::size_t at = 0; at < stream.size(); at += 7) {  // arrives in pieces
    const auto got = parser.feed(stream.data() + at, std::min<std::size_t>(7, stream.size() - at));
    frames.insert(frames.end(), got.begin(), got.end());
  }
  ASSERT_EQ(frames.size(), 4U);
  EXPECT_EQ(frames[0].message_id, kHeartbeat);
  EXPECT_EQ(decodeHeartbeat(frames[0].payload).type, 18);
  EXPECT_EQ(frames[0].component_id, 191);
  const SetPositionTargetLocalNed sp = decodeSetPositionTargetLocalNed(frames[1].payload);
  EXPECT_EQ(frames[1].sequence, 7);
  EXPECT_EQ(sp.time_boot_ms, 123456U);
  EXPECT_EQ(sp.y, -2.25F);
  EXPECT_EQ(sp.yaw_rate, -0.375F);
  EXPECT_EQ(sp.coordinate_frame, kFrameLocalNed);
  EXPECT_EQ(decodeLocalPositionNed(frames[2].payload).vz, -0.25F);
  EXPECT_EQ(decodeAttitude(frames[3].payload).yaw, 2.5F);
  EXPECT_EQ(parser.badCrc() + parser.unknownMessages(), 0U);
  EXPECT_GT(parser.skippedBytes(), 0U);
}

TEST(Mavlink, OdometryRoundTripsWithTruncationAndExtensions) {
  Odometry od;
  od.time_usec = 5'000'000;
  od.x = 1.0F, od.y = 2.0F, od.z = -3.0F;
  od.q = {0.9238795F, 0.0F, 0.0F, 0.3826834F};
  od.pose_covariance[0] = std::nanf("");
  od.frame_id = 1;
  od.child_frame_id = 12;
  od.reset_counter = 2;
  od.estimator_type = 3;
  od.quality = 100;
  // node-mavlink's frame of the same message (tools/mavlink/golden.js, "odometry").
  const auto theirs = hex(
      "fde900000901bf4b0100404b4c00000000000000803f00000040000040c05e836c3f000000000000000014efc33e0000003f000000bf00"
      "00803e000000000000003e000080be0000c07f000000000000000000000000000000000000000000000000000000000000000000000000"
      "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000c07f00000000000000"
      "00000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
      "000000000000000000000000000000000000010c0203642f61");
  od.vx = 0.5F, od.vy = -0.5F, od.vz = 0.25F, od.pitchspeed = 0.125F, od.yawspeed = -0.25F;
  od.velocity_covariance[0] = std::nanf("");
  EXPECT_EQ(frame(kOdometry, encodePayload(od), Sender{1, 191}, 9), theirs);
  Parser parser;
  const auto frames = parser.feed(theirs.data(), theirs.size());
  ASSERT_EQ(frames.size(), 1U);
  const Odometry back = decodeOdometry(frames[0].payload);
  EXPECT_EQ(back.time_usec, 5'000'000U);
  EXPECT_EQ(back.q[3], 0.3826834F);
  EXPECT_TRUE(std::isnan(back.pose_covariance[0]));
  EXPECT_EQ(back.quality, 100);

  // A message ending in zeros travels truncated and comes back whole.
  LocalPositionNed still;
  still.time_boot_ms = 77;
  still.x = 1.0F;
  const auto truncated = frame(kLocalPositionNed, encodePayload(still), Sender{}, 1);
  EXPECT_EQ(truncated[1], 8);  // time and x only
  const auto got = parser.feed(truncated.data(), truncated.size());
  ASSERT_EQ(got.size(), 1U);
  EXPECT_EQ(got[0].payload.size(), 28U);
  EXPECT_EQ(decodeLocalPositionNed(got[0].payload).x, 1.0F);
  EXPECT_EQ(decodeLocalPositionNed(got[0].payload).vz, 0.0F);
}

TEST(Mavlink, BadFramesAreCountedAndIgnoredNeverReturned) {
  Parser parser;
  auto corrupt = hex(kAttitudeHex);
  corrupt[14] ^= 0x10;  // a payload bit flipped
  EXPECT_TRUE(parser.feed(corrupt.data(), corrupt.size()).empty());
  EXPECT_EQ(parser.badCrc(), 1U);
  const auto unknown = frame(12345, {1, 2, 3}, Sender{}, 0);  // a message this codec does not know
  EXPECT_TRUE(parser.feed(unknown.data(), unknown.size()).empty());
  EXPECT_EQ(parser.unknownMessages(), 1U);
  auto signed_frame = hex(kHeartbeatHex);
  signed_frame[2] = 0x01;  // "signed": 13 more bytes follow
  signed_frame.insert(signed_frame.end(), 13, 0xAA);
  EXPECT_TRUE(parser.feed(signed_frame.data(), signed_frame.size()).empty());
  const std::vector<std::uint8_t> v1 = {0xFE, 9, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_TRUE(parser.feed(v1.data(), v1.size()).empty());
  EXPECT_EQ(parser.unsupported(), 2U);
  // Half a frame waits for the rest; random noise never crashes or returns anything.
  const auto whole = hex(kHeartbeatHex);
  EXPECT_TRUE(parser.feed(whole.data(), 10).empty());
  EXPECT_EQ(parser.feed(whole.data() + 10, whole.size() - 10).size(), 1U);
  std::mt19937 rng(5);
  std::vector<std::uint8_t> noise(100000);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  EXPECT_TRUE(parser.feed(noise.data(), noise.size()).empty());
  // After noise, a false start may hold the next frames back until its claimed length has arrived
  // (at most 265 bytes); the CRC then rejects it and the parser resynchronises one byte on: no frame
  // is lost.
  std::size_t found = 0;
  for (int i = 0; i < 30; ++i) found += parser.feed(whole.data(), whole.size()).size();
  EXPECT_EQ(found, 30U);
}

TEST(Mavlink, OnADatagramTransportAHalfFrameIsCountedAsTruncatedAndDropped) {
  // Given a UDP datagram holding one whole frame and the first 15 bytes of another,
  Parser parser;
  const auto whole = hex(kAttitudeHex);
  std::vector<std::uint8_t> datagram = whole;
  for (std::size_t i = 0; i < 15; ++i) datagram.push_back(whole[i]);
  // when it is fed and the datagram ends,
  EXPECT_EQ(parser.feed(datagram.data(), datagram.size()).size(), 1U);
  parser.endOfDatagram();
  // then the half frame is counted once and does not swallow the next datagram's frame.
  EXPECT_EQ(parser.truncated(), 1U);
  EXPECT_EQ(parser.feed(whole.data(), whole.size()).size(), 1U);
  parser.endOfDatagram();
  EXPECT_EQ(parser.truncated(), 1U);
  EXPECT_EQ(parser.badCrc(), 0U);
}

}  // namespace
}  // namespace aerotrack::hal::protocol::mavlink
