#include "libcvo/io/tum_dataset.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/support/temp_dir.hpp"

namespace cvo::io {
namespace {

namespace fs = std::filesystem;

const fs::path kSample = fs::path(CVO_TEST_DATA_DIR) / "fr1_rpy_50";
const fs::path kDesk = fs::path(CVO_SHARED_DATA_DIR) / "tum" / "fr1_desk_9frames";

bool contains(const std::exception& e, const std::string& fragment) {
  return std::string(e.what()).find(fragment) != std::string::npos;
}

TEST(TumDataset, ReadsCommittedSample) {
  const auto seq = TumSequence::open(kSample);
  ASSERT_EQ(seq.size(), 50u);
  EXPECT_DOUBLE_EQ(seq.files()[0].timestamp, 1305031229.528748);
  EXPECT_DOUBLE_EQ(seq.files()[0].depth_timestamp, 1305031229.528784);
  EXPECT_DOUBLE_EQ(seq.files()[1].timestamp, 1305031229.564425);
  EXPECT_EQ(seq.groundtruth().size(), 184u);
  EXPECT_DOUBLE_EQ(seq.intrinsics().fx, 517.3);  // tum_fr1, guessed from "fr1_rpy_50"
  EXPECT_DOUBLE_EQ(seq.intrinsics().depth_scale, 5000.0);

  const auto frame = seq.read(0);
  EXPECT_EQ(frame.index, 0u);
  EXPECT_DOUBLE_EQ(frame.timestamp, 1305031229.528748);
  EXPECT_EQ(frame.bgr.type(), CV_8UC3);
  EXPECT_EQ(frame.depth.type(), CV_16UC1);
  EXPECT_EQ(frame.bgr.size(), cv::Size(640, 480));
  EXPECT_EQ(frame.depth.size(), cv::Size(640, 480));
  EXPECT_DOUBLE_EQ(frame.intrinsics.cy, 255.3);
  // A desk scene seen from 1-2 m: the median valid depth, in metres, must say so.
  cv::Mat valid;
  frame.depth.convertTo(valid, CV_64F, 1.0 / frame.intrinsics.depth_scale);
  const double mean_m = cv::mean(valid, frame.depth > 0)[0];
  EXPECT_GT(mean_m, 0.5);
  EXPECT_LT(mean_m, 4.0);
}

TEST(TumDataset, StreamsEveryFrameInTimeOrder) {
  auto seq = TumSequence::open(kSample);
  std::size_t count = 0;
  double last = 0;
  while (const auto frame = seq.next()) {
    EXPECT_EQ(frame->index, count);
    EXPECT_GT(frame->timestamp, last);
    EXPECT_LT(std::abs(frame->timestamp - frame->depth_timestamp), 0.02);
    last = frame->timestamp;
    ++count;
  }
  EXPECT_EQ(count, 50u);
  EXPECT_FALSE(seq.next());
  seq.seek(49);
  EXPECT_EQ(seq.next()->index, 49u);
  EXPECT_THROW((void)seq.read(50), std::out_of_range);
}

TEST(TumDataset, OptionsLimitFramesAndAssociation) {
  TumOptions options;
  options.max_frames = 5;
  options.intrinsics = core::camera_preset("tum_fr3");
  const auto seq = TumSequence::open(kSample, options);
  EXPECT_EQ(seq.size(), 5u);
  EXPECT_DOUBLE_EQ(seq.intrinsics().fx, 535.4);  // the caller's camera wins over the folder name

  options.dataset.max_association_dt = 1e-6;  // the sample's pairs are ~36 µs apart at best
  try {
    TumSequence::open(kSample, options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e, "no colour image")) << e.what();
  }
  options.dataset.max_association_dt = -1;
  EXPECT_THROW(TumSequence::open(kSample, options), std::invalid_argument);
}

TEST(TumDataset, ReadsSharedDesk9FramesPng) {
  if (!fs::exists(kDesk / "rgb.txt")) GTEST_SKIP() << "shared data absent: " << kDesk << " (optional real data)";
  auto seq = TumSequence::open(kDesk);
  ASSERT_EQ(seq.size(), 9u);
  EXPECT_FALSE(seq.groundtruth().empty());
  for (std::size_t i = 0; i < 9; ++i) {
    const auto frame = seq.next();
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->bgr.type(), CV_8UC3);
    EXPECT_EQ(frame->depth.type(), CV_16UC1);
  }
  EXPECT_FALSE(seq.next());
}

TEST(TumDataset, GuessesCameraFromFolderName) {
  EXPECT_EQ(guess_camera_preset("/data/rgbd_dataset_freiburg1_rpy"), "tum_fr1");
  EXPECT_EQ(guess_camera_preset("/data/rgbd_dataset_freiburg3_long_office_household/"), "tum_fr3");
  EXPECT_EQ(guess_camera_preset("fr2_desk"), "tum_fr2");
  EXPECT_EQ(guess_camera_preset("tests/data/FR1_RPY_50"), "tum_fr1");
  EXPECT_EQ(guess_camera_preset("/data/my_recording"), std::nullopt);
  EXPECT_EQ(guess_camera_preset("/data/fr10_frames"), std::nullopt);
  EXPECT_EQ(guess_camera_preset("/data/fr1_x/rgb_frames"), std::nullopt);  // only the folder's own name counts
}

// A small TUM folder of n frames of 64x48 that tests then break in one place.
class SmallDataset {
 public:
  explicit SmallDataset(std::size_t n) : n_(n) {
    std::string rgb = "# color images\n", depth = "# depth maps\n";
    for (std::size_t i = 0; i < n; ++i) {
      rgb += stamp(i) + " rgb/" + std::to_string(i) + ".png\n";
      depth += stamp(i, 0.004) + " depth/" + std::to_string(i) + ".png\n";
      write_colour(i, cv::Mat(kSize, CV_8UC3, cv::Scalar(10, 20, 30 + static_cast<double>(i))));
      write_depth(i, cv::Mat(kSize, CV_16UC1, cv::Scalar(5000 + static_cast<double>(i))));
    }
    dir_.write("rgb.txt", rgb);
    dir_.write("depth.txt", depth);
    dir_.write("groundtruth.txt", "# gt\n" + stamp(0) + " 0 0 0 0 0 0 1\n");
    options_.intrinsics = core::Intrinsics{50, 50, 31.5, 23.5, kSize.width, kSize.height, 5000};
  }

  static std::string stamp(std::size_t i, double offset = 0) {
    std::ostringstream s;
    s.precision(17);
    s << 100.0 + 0.1 * static_cast<double>(i) + offset;
    return s.str();
  }
  [[nodiscard]] fs::path colour(std::size_t i) const { return dir_.path() / "rgb" / (std::to_string(i) + ".png"); }
  [[nodiscard]] fs::path depth(std::size_t i) const { return dir_.path() / "depth" / (std::to_string(i) + ".png"); }
  void write_colour(std::size_t i, const cv::Mat& image) const { write_png(colour(i), image); }
  void write_depth(std::size_t i, const cv::Mat& image) const { write_png(depth(i), image); }
  void write(const fs::path& relative, const std::string& text) const { dir_.write(relative, text); }
  [[nodiscard]] const fs::path& path() const { return dir_.path(); }
  [[nodiscard]] TumOptions& options() { return options_; }
  [[nodiscard]] TumSequence open() const { return TumSequence::open(dir_.path(), options_); }

  // Every frame but `bad` reads; `bad` throws a FrameError naming `file` and containing `fragment`.
  void expect_only_frame_fails(std::size_t bad, const fs::path& file, const std::string& fragment) const {
    auto seq = open();
    for (std::size_t i = 0; i < n_; ++i) {
      if (i != bad) {
        const auto frame = seq.next();
        ASSERT_TRUE(frame);
        EXPECT_EQ(frame->index, i);
        continue;
      }
      try {
        (void)seq.next();
        FAIL() << "frame " << bad << " read without error";
      } catch (const FrameError& e) {
        EXPECT_EQ(e.frame_index(), bad);
        EXPECT_EQ(e.file(), file);
        EXPECT_TRUE(contains(e, fragment)) << e.what();
        EXPECT_TRUE(contains(e, file.string())) << e.what();
      }
    }
    EXPECT_FALSE(seq.next());
  }

  static inline const cv::Size kSize{64, 48};

 private:
  static void write_png(const fs::path& file, const cv::Mat& image) {
    fs::create_directories(file.parent_path());
    ASSERT_TRUE(cv::imwrite(file.string(), image)) << file;
  }

  test::TempDir dir_{"cvo_tum"};
  std::size_t n_;
  TumOptions options_;
};

TEST(TumDataset, ReadsSmallDataset) {
  const SmallDataset data(4);
  auto seq = data.open();
  ASSERT_EQ(seq.size(), 4u);
  EXPECT_EQ(seq.groundtruth().size(), 1u);
  const auto frame = seq.read(2);
  EXPECT_EQ(frame.bgr.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 32));
  EXPECT_EQ(frame.depth.at<std::uint16_t>(0, 0), 5002);
  EXPECT_DOUBLE_EQ(frame.depth_timestamp, 100.204);
}

void expect_open_error(const SmallDataset& data, const std::string& fragment) {
  try {
    (void)data.open();
    FAIL() << "opened without error; expected: " << fragment;
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e, fragment)) << e.what();
  }
}

TEST(TumDataset, MissingFolderOrIndex) {
  EXPECT_THROW(TumSequence::open("/nonexistent/rgbd_dataset_freiburg1_xyz"), InputError);
  SmallDataset data(2);
  fs::remove(data.path() / "depth.txt");
  expect_open_error(data, "depth.txt: cannot open");
}

TEST(TumDataset, MalformedIndexLinesNameFileAndLine) {
  SmallDataset data(3);
  data.write("depth.txt", "# depth\n100.004 depth/0.png\n100.104\n");
  expect_open_error(data, "depth.txt:3: expected 2 fields");
  data.write("depth.txt", "# depth\n100.004 depth/0.png\n100.1o4 depth/1.png\n");
  expect_open_error(data, "depth.txt:3: not a number: '100.1o4'");
  data.write("rgb.txt", "# nothing\n");
  expect_open_error(data, "rgb.txt: lists no images");
}

TEST(TumDataset, UnsortedAndRepeatedLinesAreFineButAmbiguousStampsAreNot) {
  SmallDataset data(3);
  data.write("rgb.txt", "100.2 rgb/2.png\n100 rgb/0.png\n100.1 rgb/1.png\n100 rgb/0.png\n");
  auto seq = data.open();
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_DOUBLE_EQ(seq.files()[0].timestamp, 100.0);
  EXPECT_DOUBLE_EQ(seq.files()[2].timestamp, 100.2);
  data.write("rgb.txt", "100 rgb/0.png\n100.1 rgb/1.png\n100 rgb/2.png\n");
  expect_open_error(data, "rgb.txt:3: timestamp 100.000000 names a second image (first on line 1)");
}

TEST(TumDataset, NoAssociation) {
  SmallDataset data(2);
  data.write("depth.txt", "200 depth/0.png\n");
  expect_open_error(data, "no colour image of rgb.txt has a depth image of depth.txt within 0.02");
}

TEST(TumDataset, CameraNeededWhenTheNameSaysNothing) {
  SmallDataset data(1);
  data.options().intrinsics.reset();  // the temp folder's name has no fr1/fr2/fr3
  expect_open_error(data, "cannot tell the camera");
}

TEST(TumDataset, FolderCameraYamlIsUsedWhenNoneIsGiven) {
  SmallDataset data(2);
  data.options().intrinsics.reset();
  data.write("camera.yaml", "fx: 50\nfy: 51\ncx: 31.5\ncy: 23.5\nwidth: 64\nheight: 48\ndepth_scale: 1000\n");
  const auto seq = data.open();
  EXPECT_DOUBLE_EQ(seq.intrinsics().fy, 51.0);
  EXPECT_DOUBLE_EQ(seq.read(0).intrinsics.depth_scale, 1000.0);
}

TEST(TumDataset, SizeFromImagesWhenCalibrationHasNone) {
  SmallDataset data(2);
  data.options().intrinsics->width = 0;  // as an ETH3D calibration.txt gives it
  data.options().intrinsics->height = 0;
  const auto seq = data.open();
  EXPECT_EQ(seq.intrinsics().width, 64);
  EXPECT_EQ(seq.intrinsics().height, 48);
  EXPECT_EQ(seq.read(1).intrinsics.width, 64);
}

TEST(TumDataset, MissingImageFailsOnlyItsFrame) {
  const SmallDataset data(3);
  fs::remove(data.depth(1));
  data.expect_only_frame_fails(1, data.depth(1), "frame 1: image not found");
}

TEST(TumDataset, GarbageImageFailsOnlyItsFrame) {
  const SmallDataset data(3);
  std::ofstream(data.colour(1), std::ios::binary) << "this is not an image at all";
  data.expect_only_frame_fails(1, data.colour(1), "cannot decode image");
}

TEST(TumDataset, TruncatedPngFailsOnlyItsFrame) {
  const SmallDataset data(4);
  cv::Mat noise(SmallDataset::kSize, CV_16UC1);
  cv::randu(noise, 0, 60000);  // incompressible, so half the file is half the pixels
  std::vector<uchar> png;
  ASSERT_TRUE(cv::imencode(".png", noise, png));
  std::ofstream(data.depth(2), std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size() / 2));
  data.expect_only_frame_fails(2, data.depth(2), "cannot decode image");
}

TEST(TumDataset, DepthSizeDifferentFromColour) {
  const SmallDataset data(3);
  data.write_depth(1, cv::Mat(cv::Size(32, 24), CV_16UC1, cv::Scalar(1)));
  data.expect_only_frame_fails(1, data.depth(1), "depth image is 32x24 but its colour image 64x48");
}

TEST(TumDataset, ImageSizeDifferentFromCamera) {
  SmallDataset data(2);
  data.options().intrinsics = core::camera_preset("tum_fr1");  // 640x480
  auto seq = data.open();
  try {
    (void)seq.next();
    FAIL();
  } catch (const FrameError& e) {
    EXPECT_TRUE(contains(e, "image is 64x48 but the camera's 640x480")) << e.what();
  }
  EXPECT_EQ(seq.position(), 1u);
}

TEST(TumDataset, EightBitDepthIsRejected) {
  const SmallDataset data(3);
  data.write_depth(0, cv::Mat(SmallDataset::kSize, CV_8UC1, cv::Scalar(7)));
  data.expect_only_frame_fails(0, data.depth(0), "depth must be a 16-bit single-channel image, got 8-bit");
}

}  // namespace
}  // namespace cvo::io
