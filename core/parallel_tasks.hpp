// Independent tasks spread over a few threads: organs fitted side by side, dataset files written
// side by side.
#pragma once

#include <cstddef>
#include <functional>

namespace phantasm {

/// Runs task(i) for every i in [0, count) on up to `threads` threads (the caller's among them),
/// each task whole on one thread, handed out in order of i as threads come free. Tasks must not
/// depend on each other. When a task throws, no further task starts, the threads finish the
/// tasks they hold, and the first exception is rethrown.
void run_tasks_in_parallel(std::size_t count, std::size_t threads,
                           const std::function<void(std::size_t)>& task);

} // namespace phantasm
