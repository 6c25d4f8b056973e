#pragma once
// A MomentAccumulator's layout of one moment, shared by the layout (accumulator_layout.cpp) and the
// chunked kernels that read it (accumulator_chunks.cpp).

#include <cstddef>
#include <vector>

#include "momentid/accumulator.hpp"

namespace momentid {

// A moment's factors as (lag, power-table index), state factors first.
struct MomentAccumulator::Layout {
  // Kinds in working order: products with a held input, increments, the other products.
  enum Kind { kHeld, kIncrement, kPlain };
  Kind kind = kPlain;
  std::size_t state_factors = 0;
  std::vector<std::size_t> indices, lags;
};

}  // namespace momentid
