#pragma once

namespace momentid {

// Distribution functions for the statistics momentid reports, accurate to about 1e-12.

// P(X > x) for X ~ chi-square with `dof` degrees of freedom.
double chi_square_upper_tail(double x, double dof);
// P(T <= t) for T ~ Student's t with `dof` degrees of freedom.
double student_t_cdf(double t, double dof);
// The q-quantile (0 < q < 1) of Student's t with `dof` degrees of freedom.
double student_t_quantile(double q, double dof);

}  // namespace momentid
