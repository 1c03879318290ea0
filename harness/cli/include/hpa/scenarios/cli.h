#pragma once
// The `hpa` command line as a function: the `hpa` binary is one call of HpaMain, and so is a
// program of one's own that registers a controller (or an estimator, an event type, an expect key)
// first and then gets every command with it:
//
//   int main(int argc, char** argv) {
//     hpa::UsePackageDataDir(HPA_PACKAGE_DATA_DIR);  // find_package(hpa)'s hpa_DATA_DIR
//     hpa::RegisterController({"my_pid", "my PID controller", "hybrid", MakeMyPid});
//     return hpa::HpaMain(argc, argv);               // my_hpa compare --controllers my_pid,hpa_mpc
//   }
//
// examples/out_of_tree_controller builds such a program against an installed hpa; tests run
// HpaMain in-process the same way.

#include <string>

namespace hpa {

/// For a program built against an installed hpa: reads hpa's data (params.yaml, the scene, the
/// profiles, the scenarios) from `package_data_dir`, the hpa_DATA_DIR of find_package(hpa), when
/// the program finds none of its own: $HPA_DATA_DIR unset and no data in its ../share/hpa (a
/// program run from its build folder; installed into hpa's prefix, wherever that was moved, it
/// reads the prefix's). Sets $HPA_DATA_DIR (so processes it starts read the same data); does
/// nothing when `package_data_dir` holds no models/params.yaml (a prefix moved since the build:
/// the command then names the places it looked in).
void UsePackageDataDir(const std::string& package_data_dir);

/// Runs `hpa argv[1] ...` with the controllers, estimators, event types and expect keys
/// registered so far, and returns its exit code (0 ok, 1 expect failed, 2 bad input, 3 internal
/// error, 4 an output could not be written, 128 + a signal when stopped by it).
int HpaMain(int argc, char** argv);

}  // namespace hpa
