#include "media.h"

#include <dlfcn.h>
#include <limits.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// Where the module may be: the lib folder beside the executable's bin folder (the build tree and
// a relocated install), then the install prefix this build was configured for (a program linked
// against the installed libraries).
std::vector<std::string> ModuleCandidates() {
  std::vector<std::string> paths;
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n > 0) {
    std::string exe(buf, static_cast<size_t>(n));
    const std::string dir = exe.substr(0, exe.rfind('/'));
    paths.push_back(dir + "/../" HPA_MEDIA_MODULE_LIBDIR "/hpa/libhpa_media.so");
  }
  paths.push_back(HPA_MEDIA_MODULE_INSTALLED);
  return paths;
}

// The loaded module, or why it could not be loaded (loaded once per process).
struct Loaded {
  const MediaModule* module = nullptr;
  std::string error;
};

const Loaded& Load() {
  static Loaded loaded;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : ModuleCandidates()) {
      void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* why = ::dlerror();
        tried += "\n  " + path + ": " + (why != nullptr ? why : "not loadable");
        continue;
      }
      using Entry = const MediaModule* (*)();
      const auto entry = reinterpret_cast<Entry>(::dlsym(handle, kMediaModuleSymbol));
      const MediaModule* module = entry != nullptr ? entry() : nullptr;
      if (module == nullptr || module->abi_version != kMediaModuleAbiVersion) {
        tried += "\n  " + path + ": not a media module of this build";
        ::dlclose(handle);
        continue;
      }
      loaded.module = module;  // stays loaded for the process's life
      return;
    }
    loaded.error = "the image and video module libhpa_media.so could not be loaded; tried:" + tried;
  });
  return loaded;
}

const MediaModule& Module(const std::string& path) {
  const Loaded& loaded = Load();
  if (loaded.module == nullptr) throw OutputError(path, loaded.error);
  return *loaded.module;
}

}  // namespace

std::unique_ptr<VideoSink> OpenVideo(const std::string& path, const char* fourcc, double rate_hz,
                                     cv::Size frame_size) {
  return std::unique_ptr<VideoSink>(Module(path).open_video(path, fourcc, rate_hz, frame_size));
}

bool WriteImage(const std::string& path, const cv::Mat& image) {
  // whole under PartialPath (same extension: the format), then renamed: never half an image
  if (!Module(path).write_image(PartialPath(path), image)) {
    std::remove(PartialPath(path).c_str());
    return false;
  }
  CommitPartial(path);
  return true;
}

}  // namespace hpa
