#pragma once
// The band of a record's input and the white sensor noise beyond it, which would drive the
// simulation of the refinement with a force the system never felt (docs/refine.md, "Noise on
// the inputs").

#include <string>
#include <vector>

#include "momentid/refine.hpp"

namespace momentid {

// The input's band from its Welch spectrum against the level of its white noise (the mean square
// of its sixth difference, as white_noise_variance estimates it): the edge is the highest
// frequency where the spectrum exceeds InputBand::kFloorRatio times that level, the cutoff half
// as far again. `filtered` when the noise is not 0 and the cutoff lies below kMaxCutoff of the
// Nyquist frequency.
InputBand input_band(const std::string& name, const std::vector<std::vector<double>>& runs,
                     double dt);

// Removes from `x` what lies above `band.edge`: a zero-phase filter whose gain falls from 1 at the
// edge to 0 at the cutoff along a raised cosine, applied through the FFT of the series extended
// by its mirror images (no delay, no ringing from the ends).
void low_pass(std::vector<double>& x, double dt, const InputBand& band);

}  // namespace momentid
