// image_io.cpp: the one bridge from Tessera's C to OpenImageIO's C++ API,
// part of the I/O module (io_module.h).
// Reads in strips of scanlines so a large image never needs its native
// copy and its float copy in memory at once.
#include "terrain/io_module.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <sys/stat.h>
#include <vector>

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

static std::string one_line(std::string s)
{
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    if (s.size() > 300)
        s = s.substr(0, 300) + "...";
    return s;
}

static const char *attr_name = "Tessera:HeightScaleOffset";
static const char *spacing_attr = "Tessera:Spacing";
static const char *desc_spacing = "Tessera heightfield: spacing ";

// The file an image is written to, remembering a write that fell short (a
// full disk, a file size limit): OpenImageIO's PNG writer does not look at
// what its writes return, and would report a truncated file written.
class CheckedFile : public OIIO::Filesystem::IOFile {
public:
    explicit CheckedFile(const char *name) : IOFile(OIIO::string_view(name), IOProxy::Write) {}
    size_t write(const void *buf, size_t size) override
    {
        size_t n = IOFile::write(buf, size);
        failed |= n != size;
        return n;
    }
    size_t pwrite(const void *buf, size_t size, int64_t offset) override
    {
        size_t n = IOFile::pwrite(buf, size, offset);
        failed |= n != size;
        return n;
    }
    void close() override
    {
        if (m_file && (std::fflush(m_file) != 0 || std::ferror(m_file)))
            failed = true;
        if (m_file && m_auto_close) { // (IOFile's own close drops fclose's answer)
            if (std::fclose(m_file) != 0)
                failed = true;
            m_file = nullptr;
        }
        IOFile::close();
    }
    bool failed = false;
};

// Writes through a CheckedFile where out's format takes one (proxy, made
// here, must outlive out's close); false when the file cannot be opened.
static bool use_checked_file(ImageOutput *out, const char *tmp, std::unique_ptr<CheckedFile> &proxy)
{
    if (!out->supports("ioproxy"))
        return true;
    proxy.reset(new CheckedFile(tmp));
    if (!proxy->opened())
        return false;
    out->set_ioproxy(proxy.get());
    return true;
}

// Closes out (and its proxy, flushed so that a failure shows now) after
// writes that went as ok says; false, with why in e, when any part failed.
static bool finish_write(ImageOutput::unique_ptr &out, std::unique_ptr<CheckedFile> &proxy, bool ok, std::string &e)
{
    e = ok ? std::string() : one_line(out->geterror());
    if (!out->close() && ok) {
        ok = false;
        e = one_line(out->geterror());
    }
    out.reset();
    if (proxy)
        proxy->close();
    if (ok && proxy && proxy->failed) {
        ok = false;
        e = "the disk is full or the file too large";
    }
    return ok;
}

tsr_status tsr_io_image_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples,
                                     float **pixels, tsr_image_info *info, tsr_error *err)
{
    *pixels = nullptr;
    std::memset(info, 0, sizeof *info);
    struct stat st;
    if (stat(path, &st) != 0)
        return tsr_error_set(err, errno == ENOENT ? TSR_ERR_NOT_FOUND : TSR_ERR_IO, "%s: %s", path,
                             std::strerror(errno));
    if (S_ISDIR(st.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: is a folder, not an image", path);
    if (st.st_size == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "%s: empty file (0 bytes)", path);

    // Alpha as stored: OpenImageIO would otherwise multiply a PNG's colour
    // by its alpha, and heights (grey, or Terrain-RGB's colours) with it
    ImageSpec hints;
    hints.attribute("oiio:UnassociatedAlpha", 1);
    auto in = ImageInput::open(path, &hints);
    if (!in) {
        std::string e = one_line(OIIO::geterror());
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: not an image Tessera can read (%s)", path,
                             e.empty() ? "unknown format" : e.c_str());
    }
    const ImageSpec &spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: image header gives no pixels (%dx%d, %d channels)", path,
                             spec.width, spec.height, spec.nchannels);
    if (spec.depth > 1)
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: volume images (depth %d) are not heightfields", path,
                             spec.depth);
    uint64_t w = (uint64_t)spec.width, h = (uint64_t)spec.height;
    info->width = (uint32_t)std::min<uint64_t>(w, UINT32_MAX);
    info->height = (uint32_t)std::min<uint64_t>(h, UINT32_MAX);
    info->channels = (uint32_t)spec.nchannels;
    info->alpha_channel = spec.alpha_channel;
    std::snprintf(info->format, sizeof info->format, "%s", in->format_name());
    std::snprintf(info->type, sizeof info->type, "%s", spec.format.c_str());
    if (w > TSR_HEIGHTFIELD_MAX_SIDE || h > TSR_HEIGHTFIELD_MAX_SIDE || w * h > max_samples)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE,
                             "%s: image is %llux%llu; Tessera accepts at most %u per side and %llu samples", path,
                             (unsigned long long)w, (unsigned long long)h, TSR_HEIGHTFIELD_MAX_SIDE,
                             (unsigned long long)max_samples);
    if (spec.nchannels > 4)
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: %d channels; a heightfield has 1 (or RGB(A))", path,
                             spec.nchannels);
    std::string so = spec.get_string_attribute(attr_name);
    if (!so.empty() && std::sscanf(so.c_str(), "%lf %lf", &info->scale, &info->offset) == 2 &&
        std::isfinite(info->scale) && std::isfinite(info->offset) && info->scale != 0)
        info->has_scale = true;
    // the spacing: its own attribute (PNG, EXR), else the description
    // (TIFF keeps no attribute of ours)
    std::string sp = spec.get_string_attribute(spacing_attr);
    std::string desc = spec.get_string_attribute("ImageDescription");
    size_t dn = std::strlen(desc_spacing);
    const char *sp_text = !sp.empty()                                 ? sp.c_str()
                          : desc.compare(0, dn, desc_spacing) == 0 ? desc.c_str() + dn
                                                                      : nullptr;
    if (sp_text && std::sscanf(sp_text, "%lf %lf", &info->spacing[0], &info->spacing[1]) == 2 &&
        std::isfinite(info->spacing[0]) && std::isfinite(info->spacing[1]) && info->spacing[0] > 0 &&
        info->spacing[1] > 0)
        info->has_spacing = true;

    // Integer samples are read in their own type so they keep their
    // integer values; everything else is read as float.
    TypeDesc rt = TypeDesc::FLOAT;
    switch (spec.format.basetype) {
    case TypeDesc::UINT8: rt = TypeDesc::UINT8; break;
    case TypeDesc::UINT16: rt = TypeDesc::UINT16; break;
    case TypeDesc::INT16: rt = TypeDesc::INT16; break;
    case TypeDesc::INT8: rt = TypeDesc::INT8; break;
    default: break;
    }
    size_t nch = (size_t)spec.nchannels;
    size_t total = (size_t)(w * h * nch);
    float *out = (float *)tsr_alloc(alloc, total * sizeof(float));
    if (!out)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %llux%llu samples", path,
                             (unsigned long long)w, (unsigned long long)h);
    // strips of whole rows: 256, or for a tiled file (a Cloud-Optimised
    // GeoTIFF) whole rows of tiles, read with the tile API (OpenImageIO's
    // scanline reads of a tiled TIFF fail, some with SIGFPE)
    const bool tiled = spec.tile_width > 0 && spec.tile_height > 0;
    const int strip = tiled ? spec.tile_height * std::max(1, 256 / spec.tile_height) : 256;
    std::vector<unsigned char> buf;
    try {
        buf.resize((size_t)strip * (size_t)w * nch * rt.size());
    } catch (...) {
        tsr_free(alloc, out);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int y0 = 0; y0 < spec.height; y0 += strip) {
        int y1 = std::min(spec.height, y0 + strip);
        bool ok = tiled ? in->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y0, spec.y + y1, spec.z,
                                         spec.z + std::max(1, spec.depth), 0, spec.nchannels, rt, buf.data())
                        : in->read_scanlines(0, 0, spec.y + y0, spec.y + y1, 0, 0, spec.nchannels, rt, buf.data());
        if (!ok) {
            std::string e = one_line(in->geterror());
            tsr_free(alloc, out);
            return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: truncated or corrupt pixel data in rows %d to %d (%s)",
                                 path, y0, y1 - 1, e.empty() ? "read failed" : e.c_str());
        }
        size_t n = (size_t)(y1 - y0) * (size_t)w * nch;
        float *dst = out + (size_t)y0 * (size_t)w * nch;
        switch (rt.basetype) {
        case TypeDesc::UINT8:
            for (size_t i = 0; i < n; i++) dst[i] = buf[i];
            break;
        case TypeDesc::INT8:
            for (size_t i = 0; i < n; i++) dst[i] = (signed char)buf[i];
            break;
        case TypeDesc::UINT16: {
            const uint16_t *s = (const uint16_t *)buf.data();
            for (size_t i = 0; i < n; i++) dst[i] = s[i];
            break;
        }
        case TypeDesc::INT16: {
            const int16_t *s = (const int16_t *)buf.data();
            for (size_t i = 0; i < n; i++) dst[i] = s[i];
            break;
        }
        default: std::memcpy(dst, buf.data(), n * sizeof(float)); break;
        }
    }
    // A reader may report success on a file cut short; OIIO records it.
    if (in->has_error()) {
        std::string e = one_line(in->geterror());
        tsr_free(alloc, out);
        return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: truncated or corrupt pixel data (%s)", path, e.c_str());
    }
    in->close();
    *pixels = out;
    return TSR_OK;
}

tsr_status tsr_io_image_write(const char *path, const char *tmp, uint32_t width, uint32_t height,
                                      const float *values, bool as_u16, double scale, double offset, double dx,
                                      double dy, tsr_error *err)
{
    std::unique_ptr<CheckedFile> proxy; // (before out: destroyed after it)
    auto out = ImageOutput::create(tmp);
    if (!out) {
        std::string e = one_line(OIIO::geterror());
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: cannot write this image format (%s)", path, e.c_str());
    }
    ImageSpec spec((int)width, (int)height, 1, as_u16 ? TypeDesc::UINT16 : TypeDesc::FLOAT);
    spec.channelnames = {"Y"};
    char desc[256] = "";
    if (dx > 0 && dy > 0) {
        char sp[96];
        std::snprintf(sp, sizeof sp, "%.17g %.17g", dx, dy);
        spec.attribute(spacing_attr, sp);
        std::snprintf(desc, sizeof desc, "%s%s; ", desc_spacing, sp);
    }
    if (as_u16) {
        char so[96];
        std::snprintf(so, sizeof so, "%.17g %.17g", scale, offset);
        spec.attribute(attr_name, so);
        size_t n = std::strlen(desc);
        std::snprintf(desc + n, sizeof desc - n, "%sheight = value * %.17g + %.17g",
                      n ? "" : "Tessera heightfield: ", scale, offset);
    } else {
        spec.attribute("compression", "zip");
    }
    if (desc[0])
        spec.attribute("ImageDescription", desc);
    errno = 0;
    if (!use_checked_file(out.get(), tmp, proxy) || !out->open(tmp, spec)) {
        int en = errno;
        std::string e = one_line(out->geterror());
        out.reset();
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write (%s)", path,
                             !e.empty() ? e.c_str() : en ? std::strerror(en) : "unknown error");
    }
    bool ok = true;
    if (as_u16) {
        std::vector<uint16_t> row(width);
        for (uint32_t y = 0; y < height && ok; y++) {
            for (uint32_t x = 0; x < width; x++) {
                float v = values[(size_t)y * width + x];
                double q = std::isnan(v) ? 0.0 : std::floor(v + 0.5);
                row[x] = (uint16_t)std::min(65535.0, std::max(0.0, q));
            }
            ok = out->write_scanline((int)y, 0, TypeDesc::UINT16, row.data());
        }
    } else {
        ok = out->write_image(TypeDesc::FLOAT, values);
    }
    std::string e;
    ok = finish_write(out, proxy, ok, e);
    if (!ok)
        return tsr_error_set(err, TSR_ERR_IO, "%s: write failed (%s)", path, e.c_str());
    return TSR_OK;
}

// OpenImageIO's writer for path's extension; NULL, with err set, when
// there is none.
static ImageOutput::unique_ptr image_writer(const char *path, tsr_error *err)
{
    const char *slash = std::strrchr(path, '/');
    const char *dot = std::strrchr(slash ? slash + 1 : path, '.');
    if (!dot) {
        tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: no extension to choose an image format by (use .png or .tif)",
                      path);
        return nullptr;
    }
    auto out = ImageOutput::create(path);
    if (!out) {
        std::string e = one_line(OIIO::geterror());
        tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: no image writer for extension \"%s\" (use .png or .tif)%s%s%s",
                      path, dot, e.empty() ? "" : " (", e.c_str(), e.empty() ? "" : ")");
    }
    return out;
}

tsr_status tsr_io_image_save_check(const char *path, tsr_error *err)
{
    if (!path || !*path)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "no image path");
    if (!image_writer(path, err))
        return TSR_ERR_UNSUPPORTED;
    return tsr_atomic_probe(path, err);
}

tsr_status tsr_io_image_save_u8_rows(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                                     void (*fill)(void *user, uint32_t y0, uint32_t y1, uint8_t *rows), void *user,
                                     tsr_error *err)
{
    if (!path || !*path || !fill || width == 0 || height == 0 || channels == 0 || channels > 4)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: nothing to write (%ux%u, %u channels)",
                             path ? path : "(null)", width, height, channels);
    if (width > (uint32_t)INT32_MAX || height > (uint32_t)INT32_MAX)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s: image %ux%u too large to write", path, width, height);
    // The writer is picked by the extension alone: an unknown one is
    // refused before anything is created on disk.
    std::unique_ptr<CheckedFile> proxy; // (before out: destroyed after it)
    auto out = image_writer(path, err);
    if (!out)
        return TSR_ERR_UNSUPPORTED;
    ImageSpec spec((int)width, (int)height, (int)channels, TypeDesc::UINT8);
    char tmp[4096];
    tsr_status s = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (s != TSR_OK)
        return s;
    errno = 0;
    if (!use_checked_file(out.get(), tmp, proxy) || !out->open(tmp, spec)) {
        int en = errno;
        std::string e = one_line(out->geterror());
        out.reset();
        proxy.reset();
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot write (%s)", path,
                             !e.empty() ? e.c_str() : en ? std::strerror(en) : "unknown error");
    }
    // a band of rows at a time: made by fill, written, the buffer reused
    std::vector<uint8_t> band;
    try {
        band.resize((size_t)TSR_IMAGE_BAND_ROWS * width * channels);
    } catch (...) {
        out->close();
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    bool ok = true;
    for (uint32_t y0 = 0; y0 < height && ok; y0 += TSR_IMAGE_BAND_ROWS) {
        uint32_t y1 = std::min(height, y0 + (uint32_t)TSR_IMAGE_BAND_ROWS);
        fill(user, y0, y1, band.data());
        ok = out->write_scanlines((int)y0, (int)y1, 0, TypeDesc::UINT8, band.data());
    }
    std::string e;
    ok = finish_write(out, proxy, ok, e);
    proxy.reset();
    if (!ok) {
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_IO, "%s: write failed (%s)", path, e.c_str());
    }
    return tsr_atomic_commit(tmp, path, err);
}
