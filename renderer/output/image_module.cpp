// write_image and encode_image through the image writer module (see image_module.h).
#include "renderer/image_module.h"

#include <dlfcn.h>
#include <unistd.h>
#include <tbb/parallel_for.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/process/executable_path.h"
#include "renderer/render.h"

namespace nurbsrt {

namespace {

using WriteFn = decltype(&nurbsrt_write_image_v1);
using EncodeFn = decltype(&nurbsrt_encode_image_v1);
using LabelFn = decltype(&nurbsrt_draw_label_v1);

// The module's entry points.
struct ImageModule {
    WriteFn write = nullptr;
    EncodeFn encode = nullptr;
    LabelFn label = nullptr;
};

}  // namespace

std::string locate_image_module() {
    std::vector<std::string> dirs;
    const std::string beside = beside_executable(kImageModuleFile);
    dirs.push_back(beside.substr(0, beside.rfind('/')));
    // dlopen's own order for a bare name: LD_LIBRARY_PATH, then the directories
    // of ld.so.cache (those /etc/ld.so.conf.d names, on Debian), then /lib, /usr/lib.
    if (const char* env = std::getenv("LD_LIBRARY_PATH")) {
        std::string_view rest = env;
        while (!rest.empty()) {
            const size_t colon = rest.find(':');
            if (colon != 0) dirs.emplace_back(rest.substr(0, colon));
            rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
        }
    }
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator("/etc/ld.so.conf.d", ec)) {
        if (entry.path().extension() != ".conf") continue;
        std::ifstream conf(entry.path());
        for (std::string line; std::getline(conf, line);)
            if (!line.empty() && line[0] == '/') dirs.push_back(line.substr(0, line.find_first_of(" \t#")));
    }
    dirs.emplace_back("/lib");
    dirs.emplace_back("/usr/lib");
    std::string looked;
    for (const std::string& d : dirs) {
        const std::string path = (d.empty() ? "." : d) + "/" + kImageModuleFile;
        if (::access(path.c_str(), R_OK) == 0) return path;
        looked += (looked.empty() ? "" : ", ") + (d.empty() ? "." : d);
    }
    throw Error(ErrorCode::internal, std::string("cannot load the image writer module: ") + kImageModuleFile +
                                         " is not beside the executable (" + dirs.front() +
                                         ") nor on the library path (looked in " + looked + ")");
}

namespace {

// Loads the module once per process (beside the executable first, then the
// library search path) and never unloads it. RTLD_LOCAL: its libraries' symbols
// stay out of the global scope the rest of the program resolves against.
const ImageModule& load_writer() {
    static std::mutex m;
    static ImageModule module;
    std::lock_guard<std::mutex> lock(m);
    if (module.write) return module;
    const std::string beside = beside_executable(kImageModuleFile);
    void* handle = dlopen(beside.c_str(), RTLD_LAZY | RTLD_LOCAL);
    std::string why = handle ? "" : dlerror();
    if (!handle) handle = dlopen(kImageModuleFile, RTLD_LAZY | RTLD_LOCAL);
    if (!handle)
        throw Error(ErrorCode::internal, std::string("cannot load the image writer module: ") + why + "; " + dlerror());
    ImageModule found;
    found.write = reinterpret_cast<WriteFn>(dlsym(handle, kImageWriteSymbol));
    found.encode = reinterpret_cast<EncodeFn>(dlsym(handle, kImageEncodeSymbol));
    found.label = reinterpret_cast<LabelFn>(dlsym(handle, kImageLabelSymbol));
    if (!found.write || !found.encode || !found.label)
        throw Error(ErrorCode::internal,
                    std::string("image writer module without ") + (!found.write    ? kImageWriteSymbol
                                                                   : !found.encode ? kImageEncodeSymbol
                                                                                   : kImageLabelSymbol));
    module = found;
    return module;
}

// An entry point's status as write_image and encode_image answer it.
void check_status(int status, const char* message) {
    switch (status) {
        case kImageWritten:
            return;
        case kImageFormatUnsupported:
            throw Error(ErrorCode::unsupported_format, message);
        default:
            throw Error(ErrorCode::io, message);
    }
}

// The loading thread of the ImageWriterPreload alive (one at a time). Never
// destroyed: a program leaving through exit() inside the preload's scope must
// not meet a joinable thread's destructor (std::terminate).
std::thread& preload_thread() {
    static auto* loader = new std::thread;
    return *loader;
}

}  // namespace

ImageWriterPreload::ImageWriterPreload() {
    // oneTBB loads its scalable allocator (libtbbmalloc) and its thread-pool
    // server (libirml) with dlopen on first use. Had that first use to wait for
    // the loader's lock while the thread below holds it (OpenImageIO's libraries:
    // ~0.5 s of relocations), the first parallel work (the import's NURBS
    // conversion) would wait for all of it (measured: 0.6-0.8 s of
    // "nurbs_convert" for a 3-face file). So oneTBB starts here, first.
    tbb::parallel_for(0, 2, [](int) {});
    std::thread& loader = preload_thread();
    if (loader.joinable()) return;  // the one alive is loading it already
    loader = std::thread([] {
        try {
            load_writer();
        } catch (const Error&) {
            // write_image will try again and report it
        }
    });
}

ImageWriterPreload::~ImageWriterPreload() {
    std::thread& loader = preload_thread();
    if (loader.joinable()) loader.join();
}

void write_image(const RenderImage& image, const std::string& path) {
    char message[1024];
    check_status(load_writer().write(&image, path.c_str(), message, sizeof message), message);
}

void draw_label(RenderImage& image, int x, int y, int size, const std::string& text, Color colour) {
    char message[1024];
    const float rgb[3] = {colour.r, colour.g, colour.b};
    check_status(load_writer().label(&image, x, y, size, text.c_str(), rgb, message, sizeof message), message);
}

std::string encode_image(const RenderImage& image, const std::string& format_name) {
    char message[1024];
    std::string bytes;
    const auto sink = [](void* context, const void* data, size_t size) {
        static_cast<std::string*>(context)->assign(static_cast<const char*>(data), size);
    };
    check_status(load_writer().encode(&image, format_name.c_str(), sink, &bytes, message, sizeof message), message);
    return bytes;
}

}  // namespace nurbsrt
