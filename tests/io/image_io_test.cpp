// PNG files: lossless round trip for every channel count, atomic write, and bad files.
#include <gtest/gtest.h>

#include "pipeline/io/image_io.h"
#include "scratch_dir.h"
#include "sim/core/error.h"

namespace mudcrack {
namespace {

using test::ScratchDir;

Image gradient(int w, int h, int channels) {
    Image im;
    im.width = w;
    im.height = h;
    im.channels = channels;
    im.pixels.resize(size_t(w) * h * channels);
    for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = uint8_t((i * 37 + i / 7) & 0xff);
    return im;
}

TEST(PngIo, RoundTripEveryChannelCount) {
    ScratchDir dir;
    for (int channels : {1, 2, 3, 4}) {
        const Image in = gradient(37, 19, channels);
        const auto path = dir / ("img" + std::to_string(channels) + ".png");
        write_png(path, in);
        const Image out = read_png(path);
        EXPECT_EQ(out.width, 37);
        EXPECT_EQ(out.height, 19);
        EXPECT_EQ(out.channels, channels);
        EXPECT_TRUE(out.pixels == in.pixels) << channels << " channels";
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "img4.png.tmp"));
    // top row first: the first pixel on disk is pixels[0]
    EXPECT_EQ(read_png(dir / "img3.png").pixels[0], gradient(37, 19, 3).pixels[0]);
}

TEST(PngIo, BadFilesNameTheFile) {
    ScratchDir dir;
    test::expect_input_error_naming([&] { read_png(dir / "missing.png"); }, "missing.png");
    test::write_file(dir / "garbage.png", "this is not a png at all");
    test::expect_input_error_naming([&] { read_png(dir / "garbage.png"); },
                                    "garbage.png: not a PNG");
    write_png(dir / "good.png", gradient(64, 64, 4));
    const std::string good = test::read_file(dir / "good.png");
    for (size_t keep : {size_t(8), size_t(40), good.size() / 2, good.size() - 13}) {
        const std::string name = "cut" + std::to_string(keep) + ".png";
        test::write_file(dir / name, good.substr(0, keep));
        test::expect_input_error_naming([&] { read_png(dir / name); }, name);
    }
    Image wrong = gradient(4, 4, 3);
    wrong.pixels.pop_back();
    EXPECT_THROW(write_png(dir / "wrong.png", wrong), RuntimeError);
    EXPECT_FALSE(std::filesystem::exists(dir / "wrong.png"));
}

}  // namespace
}  // namespace mudcrack
