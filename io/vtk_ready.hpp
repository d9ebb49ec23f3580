// Making VTK ready for threads: a private part of the io library, called by each of its functions
// that makes VTK objects.
#pragma once

namespace phantasm {

/// Makes VTK's object factories' registry, once per process, before the caller's first VTK
/// object. VTK makes it on first use without a lock, so threads making their first VTK objects
/// at once (the dataset's files are written in parallel) each made one, and all but one leaked.
/// Safe to call from any thread: the first call makes it, the others wait for it.
void make_vtk_ready();

} // namespace phantasm
