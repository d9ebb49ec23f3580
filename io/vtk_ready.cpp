#include "io/vtk_ready.hpp"

#include <vtkObjectFactory.h>

namespace phantasm {

void make_vtk_ready() {
  // A function's static is made once, and a thread arriving meanwhile waits (C++11).
  static const bool ready = vtkObjectFactory::GetRegisteredFactories() != nullptr;
  (void)ready;
}

} // namespace phantasm
