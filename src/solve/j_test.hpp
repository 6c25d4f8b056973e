#pragma once

#include <Eigen/Dense>
#include <optional>
#include <string>

#include "momentid/fit.hpp"
#include "solve/gmm.hpp"
#include "solve/least_squares.hpp"
#include "solve/linear_system.hpp"

namespace momentid {

// Hansen's test that the equations hold at the optimally weighted estimate, calibrated for
// weights and errors from the record's own batches (see j_test.cpp). Without a test `statistic`
// and `pvalue` are empty and `warning` says why.
struct JTest {
  std::optional<double> statistic, pvalue;
  int dof = 0;  // the equations the weighting counts less the parameters
  JLaw law;     // of the p-value
  std::string warning;
};

JTest j_test(const LinearSystem& system, const LeastSquares& first, const OptimalWeighting& gmm,
             const EquationSeries& series, const KnownCovariance& known, std::size_t batches);

}  // namespace momentid
