#pragma once
// `hpa run`, `hpa compare` and `hpa render-frame` (run_command.cc, compare_command.cc,
// render_frame_command.cc), which hpa_main.cc dispatches to, and the exit codes every `hpa`
// command returns.

namespace hpa {

constexpr int kExitOk = 0;
constexpr int kExitExpectFailed = 1;  // an expect bound failed, or an unexpected crash
constexpr int kExitBadInput = 2;      // a file, key or value the message names
constexpr int kExitInternal = 3;
constexpr int kExitCannotWrite = 4;  // an output could not be written (disk full, no permission)
/// Stopped by a signal: the code is this plus the signal (130 SIGINT, 143 SIGTERM), after what
/// was computed is written.
constexpr int kExitStoppedBySignal = 128;

/// `hpa run SCENARIO.yaml ...` (argv[1] is "run"); returns the exit code.
int RunMain(int argc, char** argv);

/// `hpa compare SCENARIO.yaml --out DIR ...` (argv[1] is "compare"); returns the exit code.
int CompareMain(int argc, char** argv);

/// `hpa render-frame SCENARIO.yaml --at T --out FILE.png ...` (argv[1] is "render-frame");
/// returns the exit code.
int RenderFrameMain(int argc, char** argv);

}  // namespace hpa
