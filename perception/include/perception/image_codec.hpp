#pragma once
// The camera's frame encodings (camera_frame_t.encoding: "png" or "jpeg") to and from
// OpenCV images, with libspng and libjpeg-turbo rather than OpenCV's imgcodecs: imgcodecs
// pulls GDAL, HDF5 and a DICOM library into every process that links it, ~120 shared
// libraries whose loading was most of an hbirl command's start-up (docs/BENCHMARKS.md).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace hbirl::perception {

// An 8-bit, 3-channel BGR image (OpenCV's order) as PNG; compression_level is zlib's
// (0-9; 1, OpenCV's default, is fast and what a camera stream wants). Throws
// std::invalid_argument for another kind of image.
std::vector<std::uint8_t> encode_png(const cv::Mat& bgr, int compression_level = 1);
// The same as baseline JPEG of quality 1-100 (95: OpenCV's default), 4:2:0 chroma.
std::vector<std::uint8_t> encode_jpeg(const cv::Mat& bgr, int quality = 95);

// PNG or JPEG (told apart by their signatures) decoded to 8-bit BGR; an image whose
// header states more than max_width x max_height is refused before anything is
// allocated for it. An empty Mat when the data are not a whole, decodable image.
cv::Mat decode_image(const std::uint8_t* data, std::size_t size, int max_width = 4096, int max_height = 4096);
inline cv::Mat decode_image(const std::vector<std::uint8_t>& data, int max_width = 4096, int max_height = 4096) {
  return decode_image(data.data(), data.size(), max_width, max_height);
}

// encode_png to a file; false when it cannot be written.
bool write_png(const std::string& path, const cv::Mat& bgr);

}  // namespace hbirl::perception
