#pragma once
// Where the project's data lives (models/params.yaml, models/scene.xml, models/profiles/,
// scenarios/): an installed prefix's share/hpa, or the source tree of a build, so an installed
// binary finds its data wherever the prefix is and a build runs from its tree.

#include <string>

namespace hpa {

/// The data folder: $HPA_DATA_DIR when set (InputError if it holds no models/params.yaml);
/// else <the executable's folder>/../share/hpa when it holds models/params.yaml (an installed
/// prefix); else, for a program inside the build tree, the source tree it was built from;
/// else InputError naming the places looked in.
std::string DataDir();

/// DataDir() + "/" + relative (e.g. "models/params.yaml").
std::string DataPath(const std::string& relative);

}  // namespace hpa
