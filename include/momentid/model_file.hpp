#pragma once
// A model read from its file, for a program that hands it on (to identify) without looking into
// its equations: this header does not include GiNaC, and the Model stays an
// incomplete type (model.hpp defines it).

#include <memory>
#include <string>

namespace momentid {

class Model;

// Reads and checks a model file, as parse_model_file does: throws ParseError or ModelError naming
// file, line and column, or Error when the file cannot be read. Behind a pointer, because a
// program that includes only this header cannot hold a Model by value.
//
// Example:
//   std::shared_ptr<const Model> model = load_model("models/duffing.mom");
//   IdentifyResult r = identify(*model, DataSource::file("duffing.csv"), {.degree = 3});
std::shared_ptr<const Model> load_model(const std::string& path);

}  // namespace momentid
