#include "media.h"

#include <dlfcn.h>
#include <limits.h>
#include <link.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "hpa/models/data_dir.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// The folder of a path ("" if it has none).
std::string FolderOf(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash);
}

// The shared library that holds this code, as the dynamic loader opened it, or "" when hpa_output
// is linked into the executable (a static library: the main program's link map has no name).
std::string SharedLibraryOfThisCode() {
  Dl_info info{};
  link_map* map = nullptr;
  if (::dladdr1(reinterpret_cast<const void*>(&SharedLibraryOfThisCode), &info,
                reinterpret_cast<void**>(&map), RTLD_DL_LINKMAP) == 0 ||
      map == nullptr || map->l_name == nullptr || map->l_name[0] != '/') {
    return "";
  }
  return map->l_name;
}

// The running executable's real path (a symlink to an installed program resolved to where the
// program is), or "".
std::string ExecutablePath() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  return n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
}

// The install prefix whose share/hpa is the data folder (HPA_DATA_DIR, or beside the executable),
// or "" when the data folder is not an installed share/hpa (a source tree) or there is none.
std::string PrefixOfInstalledData() {
  std::string data;
  try {
    data = DataDir();
  } catch (const InputError&) {
    return "";  // the run reports a missing data folder itself
  }
  while (data.size() > 1 && data.back() == '/') data.pop_back();
  const std::string installed = "/share/hpa";
  if (data.size() <= installed.size() ||
      data.compare(data.size() - installed.size(), installed.size(), installed) != 0) {
    return "";
  }
  return data.substr(0, data.size() - installed.size());
}

// Where the module may be, in order: beside the object that loads it (a shared libhpa_output's
// folder's hpa/; the executable's ../lib/hpa: the build tree, an install wherever it was moved,
// a program installed into hpa's prefix); the prefix whose share/hpa is the data folder (a
// program outside the prefix pointed at it by $HPA_DATA_DIR); the install prefix this build was
// configured for.
std::vector<std::string> ModuleCandidates() {
  const std::string in_prefix = "/" HPA_MEDIA_MODULE_LIBDIR "/hpa/libhpa_media.so";
  std::vector<std::string> paths;
  const auto add = [&paths](const std::string& path) {
    if (std::find(paths.begin(), paths.end(), path) == paths.end()) paths.push_back(path);
  };
  if (const std::string library = SharedLibraryOfThisCode(); !library.empty()) {
    add(FolderOf(library) + "/hpa/libhpa_media.so");
  }
  if (const std::string exe = ExecutablePath(); !exe.empty())
    add(FolderOf(exe) + "/.." + in_prefix);
  if (const std::string prefix = PrefixOfInstalledData(); !prefix.empty()) add(prefix + in_prefix);
  add(HPA_MEDIA_MODULE_INSTALLED);
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
