#pragma once
// The `hpa` command line as a function, so tests can run it in-process (after registering a
// controller of their own, say) exactly as the binary does.

namespace hpa {

/// Runs `hpa argv[1] ...` and returns its exit code (0 ok, 1 expect failed, 2 bad input,
/// 3 internal error).
int HpaMain(int argc, char** argv);

}  // namespace hpa
