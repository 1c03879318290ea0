#pragma once
// A separate flight stack's processes and the files it shares with hpa (private to the runner).
// Both are named after the hpa process that owns them, its pid and start time
// (/tmp/hpa-flight-PID-START-XXXXXX/lockstep.sock, /dev/shm/hpa-flight-PID-START-N), and every
// process of the stack carries its socket's path in HPA_FLIGHT_SOCKET, so whatever a run leaves
// can be found and reclaimed: the stack's shell dies with hpa (PR_SET_PDEATHSIG), the run's end
// kills its process group and every process carrying its socket (a child that left the group,
// even in a session of its own), and the next hpa removes what an hpa killed outright left
// behind (kill -9: no live owner). A process that clears its environment and leaves the group
// cannot be found. Assumes /tmp and /dev/shm are not shared across PID namespaces.

#include <sys/types.h>

#include <string>

namespace hpa::runner {

/// This process as the owner of flight-stack files: "PID-START" (START: its start time in
/// clock ticks since boot, so a reused pid is another owner).
std::string FlightOwnerTag();

/// Starts `command` with /bin/sh in a process group of its own, with HPA_FLIGHT_SOCKET set to
/// `socket_path`, `path_env` as PATH, its stdout on hpa's stderr, and SIGKILL when the thread
/// that started it ends (hpa dies); returns its pid (also its process group). Throws
/// std::runtime_error when fork fails.
pid_t SpawnFlightStack(const std::string& command, const std::string& socket_path,
                       const std::string& path_env);

/// Kills (SIGKILL) every process but this one whose environment has
/// HPA_FLIGHT_SOCKET=`socket_path`, until none is left (one forked meanwhile included); returns
/// how many.
int KillProcessesOfSocket(const std::string& socket_path);

/// Reclaims what flight stacks of hpa processes that are no longer running left behind: kills
/// the processes still carrying their sockets, removes their socket folders under /tmp and their
/// frame rings in /dev/shm (this user's only; a live owner's are left alone).
void RemoveStaleFlightRuns();

}  // namespace hpa::runner
