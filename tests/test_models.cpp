#include <doctest/doctest.h>

#include <filesystem>

#include "momentid/derive.hpp"
#include "momentid/model.hpp"

TEST_SUITE("models") {
  TEST_CASE("every model in models/ parses and derives equations for all its parameters") {
    int count = 0;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::string(MOMENTID_SOURCE_DIR) + "/models")) {
      if (entry.path().extension() != ".mom") continue;
      ++count;
      const std::string path = entry.path().string();
      CAPTURE(path);
      const momentid::Model model = momentid::parse_model_file(path);
      const momentid::MomentSystem system = momentid::derive(model);
      CHECK(system.skipped.empty());
      CHECK(system.notes.empty());
      CHECK(system.generic_rank == static_cast<int>(model.parameters().size()));
      for (const auto& p : model.parameters()) {
        CHECK_MESSAGE(p.value.has_value() == (model.name().rfind("kozin_example", 0) != 0), p.name);
      }
    }
    CHECK(count == 16);
  }
}
