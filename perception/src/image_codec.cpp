// PNG (libspng) and JPEG (libjpeg-turbo's TurboJPEG API) frames (image_codec.hpp).
#include "perception/image_codec.hpp"

#include <spng.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>

namespace hbirl::perception {

namespace {

void check_bgr(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3)
    throw std::invalid_argument("image_codec: expected a non-empty 8-bit BGR image");
}

struct SpngFree {
  void operator()(spng_ctx* c) const { spng_ctx_free(c); }
};
using Spng = std::unique_ptr<spng_ctx, SpngFree>;

struct TjFree {
  void operator()(void* h) const { tjDestroy(h); }
};
using Tj = std::unique_ptr<void, TjFree>;

bool is_png(const std::uint8_t* d, std::size_t n) {
  static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return n >= 8 && std::equal(kSignature, kSignature + 8, d);
}
bool is_jpeg(const std::uint8_t* d, std::size_t n) { return n >= 3 && d[0] == 0xff && d[1] == 0xd8 && d[2] == 0xff; }

// RGB rows <-> BGR rows, in place.
void swap_red_blue(cv::Mat& image) {
  for (int y = 0; y < image.rows; ++y) {
    auto* p = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < image.cols; ++x) std::swap(p[x][0], p[x][2]);
  }
}

cv::Mat decode_png(const std::uint8_t* data, std::size_t size, int max_width, int max_height) {
  Spng ctx(spng_ctx_new(0));
  if (!ctx) return {};
  spng_set_image_limits(ctx.get(), static_cast<std::uint32_t>(max_width), static_cast<std::uint32_t>(max_height));
  spng_set_chunk_limits(ctx.get(), size, size);  // no ancillary chunk claims more than the data hold
  spng_set_crc_action(ctx.get(), SPNG_CRC_ERROR, SPNG_CRC_ERROR);
  if (spng_set_png_buffer(ctx.get(), data, size) != 0) return {};
  spng_ihdr ihdr{};
  if (spng_get_ihdr(ctx.get(), &ihdr) != 0) return {};  // also refuses sizes beyond the limits
  std::size_t bytes = 0;
  if (spng_decoded_image_size(ctx.get(), SPNG_FMT_RGB8, &bytes) != 0) return {};
  cv::Mat image(static_cast<int>(ihdr.height), static_cast<int>(ihdr.width), CV_8UC3);
  if (bytes != image.total() * image.elemSize()) return {};
  if (spng_decode_image(ctx.get(), image.data, bytes, SPNG_FMT_RGB8, SPNG_DECODE_TRNS) != 0) return {};
  swap_red_blue(image);
  return image;
}

cv::Mat decode_jpeg(const std::uint8_t* data, std::size_t size, int max_width, int max_height) {
  Tj tj(tjInitDecompress());
  if (!tj || size > static_cast<std::size_t>(std::numeric_limits<unsigned long>::max())) return {};
  int width = 0, height = 0, subsampling = 0, colourspace = 0;
  if (tjDecompressHeader3(tj.get(), data, static_cast<unsigned long>(size), &width, &height, &subsampling,
                          &colourspace) != 0)
    return {};
  if (width < 1 || height < 1 || width > max_width || height > max_height) return {};
  cv::Mat image(height, width, CV_8UC3);
  // TJFLAG_LIMITSCANS: a progressive image of thousands of scans (a decompression bomb) is refused.
  if (tjDecompress2(tj.get(), data, static_cast<unsigned long>(size), image.data, width, static_cast<int>(image.step),
                    height, TJPF_BGR, TJFLAG_LIMITSCANS | TJFLAG_STOPONWARNING) != 0) {
    return {};
  }
  return image;
}

}  // namespace

std::vector<std::uint8_t> encode_png(const cv::Mat& bgr, int compression_level) {
  check_bgr(bgr);
  cv::Mat rgb = bgr.clone();  // continuous, and ours to reorder
  swap_red_blue(rgb);
  Spng ctx(spng_ctx_new(SPNG_CTX_ENCODER));
  if (!ctx) throw std::runtime_error("image_codec: out of memory");
  spng_set_option(ctx.get(), SPNG_ENCODE_TO_BUFFER, 1);
  spng_set_option(ctx.get(), SPNG_IMG_COMPRESSION_LEVEL, compression_level);
  spng_ihdr ihdr{};
  ihdr.width = static_cast<std::uint32_t>(rgb.cols);
  ihdr.height = static_cast<std::uint32_t>(rgb.rows);
  ihdr.bit_depth = 8;
  ihdr.color_type = SPNG_COLOR_TYPE_TRUECOLOR;
  spng_set_ihdr(ctx.get(), &ihdr);
  if (const int e =
          spng_encode_image(ctx.get(), rgb.data, rgb.total() * rgb.elemSize(), SPNG_FMT_PNG, SPNG_ENCODE_FINALIZE);
      e != 0) {
    throw std::runtime_error(std::string("image_codec: PNG encoding failed: ") + spng_strerror(e));
  }
  std::size_t size = 0;
  int error = 0;
  void* png = spng_get_png_buffer(ctx.get(), &size, &error);
  if (png == nullptr)
    throw std::runtime_error(std::string("image_codec: PNG encoding failed: ") + spng_strerror(error));
  const auto* bytes = static_cast<const std::uint8_t*>(png);
  std::vector<std::uint8_t> out(bytes, bytes + size);
  std::free(png);  // the buffer is the caller's, allocated with malloc (spng.h)
  return out;
}

std::vector<std::uint8_t> encode_jpeg(const cv::Mat& bgr, int quality) {
  check_bgr(bgr);
  Tj tj(tjInitCompress());
  if (!tj) throw std::runtime_error("image_codec: out of memory");
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  if (tjCompress2(tj.get(), bgr.data, bgr.cols, static_cast<int>(bgr.step), bgr.rows, TJPF_BGR, &jpeg, &size,
                  TJSAMP_420, quality, 0) != 0) {
    const std::string why = tjGetErrorStr2(tj.get());
    tjFree(jpeg);
    throw std::runtime_error("image_codec: JPEG encoding failed: " + why);
  }
  std::vector<std::uint8_t> out(jpeg, jpeg + size);
  tjFree(jpeg);
  return out;
}

cv::Mat decode_image(const std::uint8_t* data, std::size_t size, int max_width, int max_height) {
  if (data == nullptr) return {};
  if (is_png(data, size)) return decode_png(data, size, max_width, max_height);
  if (is_jpeg(data, size)) return decode_jpeg(data, size, max_width, max_height);
  return {};
}

bool write_png(const std::string& path, const cv::Mat& bgr) {
  const std::vector<std::uint8_t> png = encode_png(bgr);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  return static_cast<bool>(out.flush());
}

}  // namespace hbirl::perception
