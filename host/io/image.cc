// image.cc — the OpenImageIO bridge behind image.h.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

extern "C" {
#include "core/error.h"
#include "core/files.h"
#include "io/image.h"
}

extern "C" int image_read_rgb(const char *path, int *width, int *height, float **rgb)
{
    *rgb = nullptr;
    // Read through ImageInput, not an ImageBuf on a file name: that goes through OpenImageIO's
    // shared ImageCache, which keeps a file's size from its first reading, so a file written
    // again in this process (a render overwritten, a test's image rewritten at another size)
    // was read into a buffer of its old size, past its end.
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return error_set(IDMR_EXIT_INPUT, "cannot read image '%s': %s", path,
                         OIIO::geterror().c_str());
    const OIIO::ImageSpec spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return error_set(IDMR_EXIT_INPUT, "image '%s' is empty", path);
    OIIO::ImageSpec float_spec(spec.width, spec.height, spec.nchannels, OIIO::TypeDesc::FLOAT);
    float_spec.channelnames = spec.channelnames;
    OIIO::ImageBuf source(float_spec);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, source.localpixels()))
        return error_set(IDMR_EXIT_INPUT, "cannot read image '%s': %s", path,
                         in->geterror().c_str());
    in->close();

    // 8-bit and 16-bit integer files hold sRGB-encoded colour; float files are linear.
    OIIO::ImageBuf linear;
    std::string space = spec.get_string_attribute("oiio:ColorSpace", "");
    bool encoded = spec.format.basetype != OIIO::TypeDesc::FLOAT &&
                   spec.format.basetype != OIIO::TypeDesc::HALF &&
                   spec.format.basetype != OIIO::TypeDesc::DOUBLE;
    if (space == "Linear" || space == "linear")
        encoded = false;
    const OIIO::ImageBuf *pixels = &source;
    if (encoded) {
        if (!OIIO::ImageBufAlgo::colorconvert(linear, source, "sRGB", "linear"))
            return error_set(IDMR_EXIT_INPUT, "image '%s': sRGB to linear conversion failed: %s",
                             path, linear.geterror().c_str());
        pixels = &linear;
    }

    size_t count = (size_t)spec.width * (size_t)spec.height;
    float *out = (float *)xmalloc(3 * sizeof(float) * count);
    int channels = spec.nchannels;
    float *all = (float *)xmalloc(sizeof(float) * count * (size_t)channels);
    pixels->get_pixels(OIIO::ROI(0, spec.width, 0, spec.height, 0, 1, 0, channels),
                       OIIO::TypeDesc::FLOAT, all);
    for (size_t p = 0; p < count; p++)
        for (int c = 0; c < 3; c++)
            out[3 * p + c] = all[p * (size_t)channels + (channels >= 3 ? c : 0)];
    std::free(all);
    *width = spec.width;
    *height = spec.height;
    *rgb = out;
    return 0;
}

extern "C" void image_false_colour(float t, unsigned char rgb[3])
{
    static const float stops[5][3] = {{0.0f, 0.0f, 0.02f},
                                      {0.35f, 0.05f, 0.55f},
                                      {0.85f, 0.15f, 0.25f},
                                      {0.98f, 0.55f, 0.05f},
                                      {1.0f, 0.98f, 0.75f}};
    if (!(t > 0.0f))
        t = 0.0f;
    if (t > 1.0f)
        t = 1.0f;
    float x = t * 4.0f;
    int i = x >= 4.0f ? 3 : (int)x;
    float f = x - (float)i;
    for (int c = 0; c < 3; c++) {
        float v = stops[i][c] + f * (stops[i + 1][c] - stops[i][c]);
        rgb[c] = (unsigned char)(v * 255.0f + 0.5f);
    }
}

// Encodes the image in memory (the format chosen by the extension of `path`), then writes the
// bytes through files_write_atomic(), which checks every write and the close: OpenImageIO's own
// file output lets a failed write pass (on a full disk a 0-byte PNG came out as written). A
// format whose writer takes no IOProxy goes to a temporary file of its extension instead, and
// is accepted only where the file is not empty.
static int write_image(const char *path, int width, int height, OIIO::TypeDesc file_type,
                       OIIO::TypeDesc pixel_type, const void *pixels)
{
    std::string target(path);
    OIIO::ImageSpec spec(width, height, 3, file_type);
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput memory(bytes);
    auto out = OIIO::ImageOutput::create(target, &memory);
    if (!out)
        return error_set(IDMR_EXIT_FAILURE, "cannot write image '%s': %s", path,
                         OIIO::geterror().c_str());
    if (out->supports("ioproxy")) {
        bool ok = out->open(target, spec) && out->write_image(pixel_type, pixels) && out->close();
        std::string reason = out->geterror();
        out.reset();
        if (!ok)
            return error_set(IDMR_EXIT_FAILURE, "cannot write image '%s': %s", path,
                             reason.c_str());
        return files_write_atomic(path, bytes.data(), bytes.size());
    }
    out.reset();
    size_t dot = target.find_last_of('.');
    std::string extension = dot == std::string::npos ? "" : target.substr(dot);
    std::vector<char> name(target.size() + extension.size() + 32);
    int fd = files_create_temporary(path, extension.c_str(), name.data(), name.size());
    if (fd < 0)
        return -1;
    close(fd);
    out = OIIO::ImageOutput::create(name.data());
    if (!out) {
        unlink(name.data());
        return error_set(IDMR_EXIT_FAILURE, "cannot write image '%s': %s", path,
                         OIIO::geterror().c_str());
    }
    bool ok = out->open(name.data(), spec) && out->write_image(pixel_type, pixels) && out->close();
    std::string reason = ok ? "the file came out empty" : out->geterror();
    out.reset();
    struct stat written;
    ok = ok && stat(name.data(), &written) == 0 && written.st_size > 0;
    if (!ok || rename(name.data(), path) != 0) {
        unlink(name.data());
        return error_set(IDMR_EXIT_FAILURE, "cannot write image '%s': %s", path,
                         ok ? strerror(errno) : reason.c_str());
    }
    return 0;
}

extern "C" int image_write_rgb_float(const char *path, int width, int height, const float *rgb)
{
    // 32-bit floats: half floats end at 65504, and a bright light's pixels would become inf.
    return write_image(path, width, height, OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::FLOAT, rgb);
}

extern "C" int image_info(const char *path, int *width, int *height, int *channels)
{
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return error_set(IDMR_EXIT_INPUT, "cannot read image '%s': %s", path,
                         OIIO::geterror().c_str());
    const OIIO::ImageSpec &spec = in->spec();
    *width = spec.width;
    *height = spec.height;
    *channels = spec.nchannels;
    in->close();
    return 0;
}

extern "C" int image_write_rgb8(const char *path, int width, int height, const unsigned char *rgb)
{
    return write_image(path, width, height, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, rgb);
}
