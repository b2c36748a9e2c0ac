// The flight controller's MAVLink parser (as a byte stream and as datagrams) and the gimbal motor's
// CAN reply codec: the bytes a device, or an attacker on its link, sends us.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "aerotrack/hal/protocol/mavlink.hpp"
#include "aerotrack/hal/protocol/rmd.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace mavlink = aerotrack::hal::protocol::mavlink;
  namespace rmd = aerotrack::hal::protocol::rmd;
  mavlink::Parser stream;
  for (const mavlink::Frame& f : stream.feed(data, size)) {  // every known message's payload decoded
    switch (f.message_id) {
      case 0:
        (void)mavlink::decodeHeartbeat(f.payload);
        break;
      case 30:
        (void)mavlink::decodeAttitude(f.payload);
        break;
      case 32:
        (void)mavlink::decodeLocalPositionNed(f.payload);
        break;
      case 84:
        (void)mavlink::decodeSetPositionTargetLocalNed(f.payload);
        break;
      case 331:
        (void)mavlink::decodeOdometry(f.payload);
        break;
      default:
        break;
    }
  }
  mavlink::Parser datagrams;  // the same bytes in datagrams of 1..64 bytes, sized by the data
  for (std::size_t i = 0; i < size;) {
    const std::size_t n = std::min<std::size_t>(size - i, 1 + data[i] % 64);
    datagrams.feedEach(data + i, n, [](const mavlink::FrameView&) {});
    datagrams.endOfDatagram();
    i += n;
  }
  for (std::size_t i = 0; i + 10 <= size; i += 10) {  // CAN frames: id (2 bytes), length, 8 data bytes
    rmd::CanFrame frame;
    frame.id = static_cast<std::uint32_t>(data[i] | (data[i + 1] << 8U)) & 0x7FFU;
    frame.length = data[i + 2] % 9;
    std::copy(data + i + 2, data + i + 10, frame.data.begin());
    (void)rmd::decodeReply(1 + data[i] % 32, frame);
  }
  return 0;
}
