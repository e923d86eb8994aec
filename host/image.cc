// image.cc — the OpenImageIO bridge behind image.h.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <cstdlib>
#include <cstring>
#include <string>

extern "C" {
#include "error.h"
#include "image.h"
}

extern "C" int image_read_rgb(const char *path, int *width, int *height, float **rgb)
{
    *rgb = nullptr;
    OIIO::ImageBuf source(path);
    if (!source.read(0, 0, true, OIIO::TypeDesc::FLOAT))
        return error_set(IDMR_EXIT_INPUT, "cannot read image '%s': %s", path,
                         source.geterror().c_str());
    const OIIO::ImageSpec &spec = source.spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return error_set(IDMR_EXIT_INPUT, "image '%s' is empty", path);

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
