#include "solve/distributions.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace momentid {

double f_upper_tail(double x, double dof1, double dof2) {
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f(dof1, dof2), x));
}

double chi_square_upper_tail(double x, double dof) {
  if (!(x > 0)) return 1;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), x));
}

double chi_square_quantile(double q, double dof) {
  return boost::math::quantile(boost::math::chi_squared(dof), q);
}

double student_t_quantile(double q, double dof) {
  return boost::math::quantile(boost::math::students_t(dof), q);
}

}  // namespace momentid
