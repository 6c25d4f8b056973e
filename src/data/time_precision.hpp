#pragma once

namespace momentid::data {

// The precision to which a column of time stamps was written: the unit in the last decimal
// place of the value with the most decimals seen so far (1e-6 for times printed to 6 decimals),
// or 0 once a value has more decimals than a double resolves (a float32 or float64 value that
// was never rounded to decimals). Time stamps rounded to that unit from equally spaced times
// have steps that differ by at most one unit, so a step may differ from another by that much.
//
// Example:
//   TimePrecision p;
//   p.see(0.000977);
//   p.unit();  // 1e-6
class TimePrecision {
 public:
  void see(double t);
  double unit() const;

 private:
  int decimals_ = 0;
  double scale_ = 1;  // 10^decimals_
  bool binary_ = false;
};

}  // namespace momentid::data
