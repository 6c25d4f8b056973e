#include "momentid/model_file.hpp"

#include "momentid/algebra_lock.hpp"
#include "momentid/model.hpp"

namespace momentid {

std::shared_ptr<const Model> load_model(const std::string& path) {
  const AlgebraLock lock;
  return std::make_shared<const Model>(parse_model_file(path));
}

}  // namespace momentid
