#pragma once
// The size an encoded camera frame's own header states, read without decoding it. A
// decoder allocates what the header says (OpenCV's up to 2^30 pixels, gigabytes) before
// it reads a pixel, and the header is the sender's, like the message's width and height
// around it: a 167-byte PNG stating 30000 x 30000 made a receiver allocate 2.7 GB
// (tests/fuzz/RESULTS.md). So every receiver checks the header against the message (and
// the message against its limits) first, and decodes only PNG or JPEG bytes: OpenCV
// picks its decoder by the bytes, not by the message's encoding field.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

namespace hbirl::services {

// (width, height) from a PNG's IHDR (encoding "png") or a JPEG's start-of-frame segment
// ("jpeg"); nullopt when the bytes do not begin as that encoding says.
inline std::optional<std::pair<long, long>> encoded_frame_size(const std::uint8_t* d, std::size_t size,
                                                               const std::string& encoding) {
  const auto be16 = [d](std::size_t i) { return static_cast<long>(d[i]) << 8 | d[i + 1]; };
  if (encoding == "png") {
    // The signature, then the IHDR chunk: length (4), "IHDR", width (4), height (4).
    static const std::uint8_t kStart[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    if (size < 24) return std::nullopt;
    for (std::size_t i = 0; i < sizeof kStart; ++i) {
      if (d[i] != kStart[i]) return std::nullopt;
    }
    return std::make_pair(be16(16) << 16 | be16(18), be16(20) << 16 | be16(22));
  }
  if (encoding == "jpeg") {
    // SOI, then marker segments up to the first SOFn (what libjpeg reads the size from).
    if (size < 3 || d[0] != 0xff || d[1] != 0xd8) return std::nullopt;
    std::size_t pos = 2;
    while (pos + 4 <= size) {
      if (d[pos] != 0xff) return std::nullopt;
      const std::uint8_t marker = d[pos + 1];
      if (marker == 0xff) {  // fill byte
        ++pos;
        continue;
      }
      if (marker == 0xda || marker == 0xd9 || marker == 0xd8 || marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) {
        return std::nullopt;  // scan data, the end or a stray marker before any frame header
      }
      const long length = be16(pos + 2);
      if (length < 2) return std::nullopt;
      if (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc) {
        if (pos + 9 > size) return std::nullopt;  // FF Cn, length, precision, height, width
        return std::make_pair(be16(pos + 7), be16(pos + 5));
      }
      pos += 2 + static_cast<std::size_t>(length);
    }
  }
  return std::nullopt;
}

}  // namespace hbirl::services
