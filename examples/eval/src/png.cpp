// SvgToPng: a report plot rendered to PNG by librsvg onto a cairo image surface.
#include <cairo.h>
#include <librsvg/rsvg.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "driftcorr/eval/report.h"

namespace driftcorr::eval {
namespace {

struct HandleFree {
    void operator()(RsvgHandle* h) const { g_object_unref(h); }
};
struct SurfaceFree {
    void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextFree {
    void operator()(cairo_t* c) const { cairo_destroy(c); }
};

// librsvg's message, and the GError freed.
std::string Take(GError* error) {
    const std::string message = error && error->message ? error->message : "unknown error";
    if (error) g_error_free(error);
    return message;
}

cairo_status_t Append(void* closure, const unsigned char* data, unsigned int length) {
    static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
    return CAIRO_STATUS_SUCCESS;
}

}  // namespace

std::string SvgToPng(const std::string& svg) {
    GError* error = nullptr;
    const std::unique_ptr<RsvgHandle, HandleFree> handle(
        rsvg_handle_new_from_data(reinterpret_cast<const guint8*>(svg.data()), svg.size(), &error));
    if (!handle) throw std::runtime_error("the plot cannot be read as SVG: " + Take(error));
    double width = 0.0, height = 0.0;
    if (!rsvg_handle_get_intrinsic_size_in_pixels(handle.get(), &width, &height) ||
        !(width >= 1.0 && height >= 1.0 && width <= 20000.0 && height <= 20000.0)) {
        throw std::runtime_error("the plot has no pixel size to render at");
    }
    const std::unique_ptr<cairo_surface_t, SurfaceFree> surface(
        cairo_image_surface_create(CAIRO_FORMAT_ARGB32, static_cast<int>(std::ceil(width)),
                                   static_cast<int>(std::ceil(height))));
    const std::unique_ptr<cairo_t, ContextFree> cr(cairo_create(surface.get()));
    const RsvgRectangle viewport{0.0, 0.0, width, height};
    if (!rsvg_handle_render_document(handle.get(), cr.get(), &viewport, &error)) {
        throw std::runtime_error("the plot cannot be rendered: " + Take(error));
    }
    std::string png;
    const cairo_status_t status = cairo_surface_write_to_png_stream(surface.get(), &Append, &png);
    if (status != CAIRO_STATUS_SUCCESS) {
        throw std::runtime_error(std::string("the plot cannot be encoded as PNG: ") +
                                 cairo_status_to_string(status));
    }
    return png;
}

}  // namespace driftcorr::eval
