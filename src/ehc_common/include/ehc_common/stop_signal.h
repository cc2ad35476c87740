#pragma once
// Stop signals for long offline runs (ehc_experiment): SIGINT and SIGTERM set a flag instead of
// killing the process, the runners poll it between runs (or cycles) and return what they have
// completed, and the tool writes those partial results and exits 128 + the signal (130 on Ctrl-C,
// 143 on SIGTERM). A second signal of either kind ends the process at once (the default
// action), for a run that does not stop. ROS-free.

namespace ehc_common {

/// Installs the handlers (the first signal restores the default action of both).
void installStopSignals();
/// A stop signal arrived (or requestStop was called).
bool stopRequested();
/// The signal that asked to stop (0: none).
int stopSignal();
/// 128 + stopSignal() (the shell's convention), 0 when no stop was requested.
int stopExitCode();
/// As if `signal` had arrived (tests); 0 clears the request.
void requestStop(int signal);

}  // namespace ehc_common
