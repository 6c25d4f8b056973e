#pragma once
// The setters of option_table(), one per option, and the readers of the kinds of value they
// share. Each reads the text of its option, checks it and stores it in SelectOptions, naming the
// option `name` in its messages (option_table.hpp).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "momentid/option_table.hpp"

namespace momentid::options {

// A whole number, 0 or more; within [low, high] when given.
std::size_t count(const std::string& text, const std::string& name);
std::size_t count_in(const std::string& text, const std::string& name, std::size_t low,
                     std::size_t high);
// Names separated by commas; an empty text is none.
std::vector<std::string> names(const std::string& text);

// The record and how a pass reads it.
void set_columns(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_dt(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_hold(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_input_shift(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n);
void set_batches(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_lags(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_integrate(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_integrate_corner(SelectOptions& o, const Model& m, const std::string& text,
                          const std::string& n);
void set_skip_rows(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_decimal(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_missing(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_names(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_runs(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_dt_from(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_threads(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_shard_size(SelectOptions& o, const Model& m, const std::string& text,
                    const std::string& n);

// Against the completed model.
void set_instruments(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n);
void set_noise(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_fix(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_center(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_multipliers(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n);

// identify's own.
void set_degree(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_method(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_weighting(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_extrapolate(SelectOptions& o, const Model& m, const std::string& text,
                     const std::string& n);

// select's own.
void set_exhaustive(SelectOptions& o, const Model& m, const std::string& text,
                    const std::string& n);
void set_ranked(SelectOptions& o, const Model& m, const std::string& text, const std::string& n);
void set_validation(SelectOptions& o, const Model& m, const std::string& text,
                    const std::string& n);

}  // namespace momentid::options
