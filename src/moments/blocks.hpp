#pragma once
// Delivering a reader's blocks to the accumulating code, on the same thread or on a reading
// thread of its own.

#include <cstddef>
#include <functional>

#include "momentid/reader.hpp"

namespace momentid {

// Rows per block read.
inline constexpr std::size_t kBlockRows = 1 << 15;

// Delivers the blocks of `reader` to `consume`, in order. `pipelined`: the reader runs on a
// thread of its own, a few blocks ahead. An exception of either side ends both and is rethrown.
void for_each_block(DataReader& reader, bool pipelined,
                    const std::function<void(DataBlock&)>& consume);

}  // namespace momentid
