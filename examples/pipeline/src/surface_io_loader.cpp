// The definitions of what driftcorr/pipeline/surface_io_loader.h declares.
#include "driftcorr/pipeline/surface_io_loader.h"

#include <stdexcept>
#include <string>

#ifndef DRIFTCORR_SURFACE_IO_LINKED
#include <dlfcn.h>

#include <filesystem>
#endif

namespace driftcorr::pipeline {

#ifdef DRIFTCORR_SURFACE_IO_LINKED

const SurfaceIoApi& SurfaceIo() { return *driftcorr_surface_io_api(); }

#else

namespace {

// The library by its soname (the search path of this library's RUNPATH, LD_LIBRARY_PATH, the
// system's), then beside this library, then where the build tree put it.
const SurfaceIoApi* Load() {
    std::string reasons;
    auto try_open = [&](const std::string& name) -> void* {
        void* h = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (h == nullptr) {
            const char* e = dlerror();
            reasons += std::string("\n  ") + (e != nullptr ? e : name);
        }
        return h;
    };
    void* handle = try_open(DRIFTCORR_SURFACE_IO_SONAME);
    Dl_info self{};
    if (handle == nullptr && dladdr(reinterpret_cast<void*>(&Load), &self) != 0 &&
        self.dli_fname != nullptr) {
        const std::filesystem::path beside =
            std::filesystem::path(self.dli_fname).parent_path() / DRIFTCORR_SURFACE_IO_SONAME;
        handle = try_open(beside.string());
    }
    if (handle == nullptr) handle = try_open(DRIFTCORR_SURFACE_IO_BUILD_PATH);
    if (handle == nullptr) {
        throw std::runtime_error(std::string("cannot load ") + DRIFTCORR_SURFACE_IO_SONAME +
                                 " (point-cloud and OctoMap maps):" + reasons);
    }
    using Entry = const SurfaceIoApi* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, "driftcorr_surface_io_api"));
    if (entry == nullptr) {
        throw std::runtime_error(std::string(DRIFTCORR_SURFACE_IO_SONAME) +
                                 " has no driftcorr_surface_io_api");
    }
    return entry();
}

}  // namespace

const SurfaceIoApi& SurfaceIo() {
    static const SurfaceIoApi* api = Load();  // once; a failure is retried on the next call
    return *api;
}

#endif

}  // namespace driftcorr::pipeline
