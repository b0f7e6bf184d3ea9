#pragma once
/// The supervisor's exit statuses (docs/ARCHITECTURE.md: 0 ok, 1 runtime failure, 2 bad command line
/// or config, 3 finished but not converged).
namespace shapeform::supervisor {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;
inline constexpr int kExitBadInput = 2;
/// A wait timed out, or was ended by another participant's command.
inline constexpr int kExitWaitTimedOut = 3;
/// Two Ctrl-C within a second on an empty console line (128 + SIGINT, as a shell reports it).
inline constexpr int kExitInterrupted = 130;

}  // namespace shapeform::supervisor
