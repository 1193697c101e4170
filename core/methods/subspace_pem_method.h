#pragma once
// The `auto` method (auto_method.cc), registered with the subspace and prediction-error
// methods (subspace_pem_method.cc).
#include "core/methods/registry.h"

namespace idrig {

// Chooses among the applicable methods and orders by simulation fit on held-out data.
MethodInfo AutoMethod();

}  // namespace idrig
