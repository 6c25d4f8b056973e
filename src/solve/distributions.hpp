#pragma once

namespace momentid {

// Distribution functions for the statistics momentid reports (Boost.Math).

// P(X > x) for X ~ F with `dof1` and `dof2` degrees of freedom.
double f_upper_tail(double x, double dof1, double dof2);
// P(X > x) for X ~ chi-square(dof); 1 for x <= 0.
double chi_square_upper_tail(double x, double dof);
// The q-quantile (0 < q < 1) of Student's t with `dof` degrees of freedom.
double student_t_quantile(double q, double dof);
// The q-quantile (0 < q < 1) of chi-square(dof), dof > 0.
double chi_square_quantile(double q, double dof);

}  // namespace momentid
