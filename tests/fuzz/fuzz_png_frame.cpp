// libFuzzer target: the camera frame decoders -- a CAMERA message whose data is the input,
// through PerceptionService (perception/image_codec.hpp's decoder, then the blob detector), the labeller and
// the dashboard (which decodes the frame again to annotate it, frame_png()). The message's
// width and height are the image header's when it states a size in range (so well-formed
// frames get past the size checks to the detector), else 1x1: a hostile header must be
// refused before anything decodes it. Input starting like a JPEG is sent as one.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "dashboard/state.hpp"
#include "services/frame_header.hpp"
#include "services/labeller_service.hpp"
#include "services/memory_bus.hpp"
#include "services/perception_service.hpp"
#include "sim_driver/registry/domain.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hbirl::services;
  if (size < 1 || size > (1u << 22)) return 0;
  hbirl::camera_frame_t m{};
  m.utime = 1;
  m.width = 1, m.height = 1;
  m.encoding = size >= 2 && data[0] == 0xff && data[1] == 0xd8 ? "jpeg" : "png";
  // The header's size, as an honest sender states it, when it is one a receiver takes;
  // else 1x1 (and the receivers must refuse the frame before decoding it).
  if (const auto stated = encoded_frame_size(data, size, m.encoding)) {
    if (stated->first >= 1 && stated->first <= 4096 && stated->second >= 1 && stated->second <= 4096) {
      m.width = static_cast<std::int16_t>(stated->first), m.height = static_cast<std::int16_t>(stated->second);
    }
  }
  m.size = static_cast<std::int32_t>(size);
  m.data.assign(data, data + size);

  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters counters;
  counters.service = "fuzz";
  counters.quiet = true;
  PerceptionService perception(bus, counters);
  LabellerService labeller(bus, counters, *hbirl::builtin_domain("onion")->camera());
  hbirl::dashboard::DashboardState dashboard;
  dashboard.subscribe(bus, counters);
  // The dashboard keeps frames of the onion domain (its marker makes the page's names).
  hbirl::episode_marker_t marker{};
  marker.domain = "onion";
  marker.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
  marker.num_steps = 1;
  marker.frames_per_step = 1;
  publish(bus, channels::kEpisode, marker, counters);
  publish(bus, channels::kCamera, m, counters);
  // CAMERA -> DETECTIONS -> OBSERVATIONS, each reaching the dashboard.
  for (int round = 0; round < 4 && bus.handle(0) > 0; ++round) {
  }
  dashboard.frame_png();
  return 0;
}
