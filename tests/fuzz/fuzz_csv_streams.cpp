// A recording's CSV streams and the dataset manifest. The first byte picks a stream; the harness
// writes that stream's header (a fuzzer would rarely find one by chance) and the rest as its rows,
// read strictly and then leniently, each record decoded by the stream's codec. The manifest gets
// the bytes as they are.
#include <cstddef>
#include <cstdint>
#include <string>

#include "aerotrack/hal/replay/csv_stream.hpp"
#include "aerotrack/hal/replay/manifest.hpp"
#include "aerotrack/hal/replay/stream_codecs.hpp"
#include "fuzz_input.hpp"

namespace {

using namespace aerotrack::hal::replay;  // NOLINT(google-build-using-namespace): the codecs

template <class Codec>
void readStream(const std::uint8_t* data, std::size_t size) {
  std::string file = "stamp_ns";
  for (const std::string& c : Codec::columns()) file += "," + c;
  file += "\n" + aerotrack::fuzz::text(data, size);
  const aerotrack::fuzz::MemoryFile memory(reinterpret_cast<const std::uint8_t*>(file.data()), file.size());  // NOLINT
  for (const BadRowPolicy policy : {BadRowPolicy::kStrict, BadRowPolicy::kSkip}) {
    auto reader = CsvStreamReader::open(memory.path(), Codec::columns(), policy);
    if (!reader) continue;
    for (int i = 0; i < 100000; ++i) {
      auto record = reader->next();
      if (!record || !record->has_value()) break;
      (void)Codec::decode(**record, "fuzz.csv");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  switch (data[0] % 6) {
    case 0:
      readStream<DeliveredOdometryCodec>(data + 1, size - 1);
      break;
    case 1:
      readStream<DeliveredGimbalStateCodec>(data + 1, size - 1);
      break;
    case 2:
      readStream<DeliveredDetectionCodec>(data + 1, size - 1);
      break;
    case 3:
      readStream<SetpointCodec>(data + 1, size - 1);
      break;
    case 4:
      readStream<DeliveredFrameIndexCodec>(data + 1, size - 1);
      break;
    default: {
      const aerotrack::fuzz::MemoryFile memory(data + 1, size - 1);
      (void)readManifest(memory.path());
    }
  }
  return 0;
}
