// The frame codecs (perception/image_codec.hpp) against independent truth: PNG is
// lossless (every pixel back), JPEG close, and what is not a whole image is refused
// without allocating what its header claims.
#include "perception/image_codec.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "learner/rng.hpp"

namespace hbirl::perception {
namespace {

cv::Mat noise_image(int width, int height, std::uint64_t seed) {
  cv::Mat image(height, width, CV_8UC3);
  Rng rng(seed);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      image.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(rng.uniform_int(256)), static_cast<uchar>(rng.uniform_int(256)),
                    static_cast<uchar>(rng.uniform_int(256)));
  }
  return image;
}

TEST(ImageCodec, PngRoundTripsEveryPixelInBgrOrder) {
  const cv::Mat image = noise_image(37, 23, 1);
  for (int level : {0, 1, 9}) {
    const std::vector<std::uint8_t> png = encode_png(image, level);
    const cv::Mat back = decode_image(png);
    ASSERT_EQ(back.size(), image.size());
    ASSERT_EQ(back.type(), CV_8UC3);
    EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0) << "level " << level;
  }
  // Channel order: a pure blue image (BGR 255, 0, 0) stays blue.
  const cv::Mat blue(4, 4, CV_8UC3, cv::Scalar(255, 0, 0));
  EXPECT_EQ(decode_image(encode_png(blue)).at<cv::Vec3b>(0, 0), cv::Vec3b(255, 0, 0));
}

TEST(ImageCodec, JpegRoundTripsCloselyInBgrOrder) {
  cv::Mat image(64, 96, CV_8UC3);
  cv::rectangle(image, {0, 0, 96, 64}, cv::Scalar(20, 160, 230), cv::FILLED);  // a smooth image: JPEG's case
  cv::circle(image, {48, 32}, 20, cv::Scalar(200, 40, 10), cv::FILLED);
  const cv::Mat back = decode_image(encode_jpeg(image, 95));
  ASSERT_EQ(back.size(), image.size());
  cv::Mat diff;
  cv::absdiff(back, image, diff);
  // 4:2:0 chroma costs a few levels at saturated edges; a swapped or shifted channel would cost ~100.
  EXPECT_LT(cv::mean(diff)[0] + cv::mean(diff)[1] + cv::mean(diff)[2], 3 * 6.0);
  EXPECT_NEAR(back.at<cv::Vec3b>(32, 48)[0], 200, 12);  // blue channel of the circle
}

TEST(ImageCodec, RefusesWhatIsNotAWholeImage) {
  const std::vector<std::uint8_t> png = encode_png(noise_image(16, 16, 2));
  const std::vector<std::uint8_t> jpeg = encode_jpeg(noise_image(16, 16, 3), 80);
  EXPECT_TRUE(
      decode_image(std::vector<std::uint8_t>(png.begin(), png.begin() + static_cast<long>(png.size() / 2))).empty());
  EXPECT_TRUE(
      decode_image(std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + static_cast<long>(jpeg.size() / 2))).empty());
  EXPECT_TRUE(decode_image(std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9}).empty());
  EXPECT_TRUE(decode_image(nullptr, 0).empty());
  std::vector<std::uint8_t> corrupt = png;
  corrupt[png.size() / 2] ^= 0xff;  // a flipped byte in the image data: its CRC fails
  EXPECT_TRUE(decode_image(corrupt).empty());
}

TEST(ImageCodec, RefusesImagesLargerThanTheLimitBeforeDecoding) {
  const std::vector<std::uint8_t> png = encode_png(noise_image(40, 30, 4));
  EXPECT_FALSE(decode_image(png.data(), png.size(), 40, 30).empty());
  EXPECT_TRUE(decode_image(png.data(), png.size(), 39, 30).empty());
  EXPECT_TRUE(decode_image(png.data(), png.size(), 40, 29).empty());
  const std::vector<std::uint8_t> jpeg = encode_jpeg(noise_image(40, 30, 5));
  EXPECT_FALSE(decode_image(jpeg.data(), jpeg.size(), 40, 30).empty());
  EXPECT_TRUE(decode_image(jpeg.data(), jpeg.size(), 39, 30).empty());
}

TEST(ImageCodec, EncodingRefusesAnotherKindOfImage) {
  EXPECT_THROW(encode_png(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(encode_png(cv::Mat(4, 4, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(encode_jpeg(cv::Mat(4, 4, CV_16UC3)), std::invalid_argument);
}

}  // namespace
}  // namespace hbirl::perception
