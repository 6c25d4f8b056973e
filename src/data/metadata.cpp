#include "momentid/metadata.hpp"

#include <set>

#include "data/format.hpp"

namespace momentid {

std::optional<std::string> DataMetadata::get(const std::string& key) const {
  for (auto line = lines_.rbegin(); line != lines_.rend(); ++line) {
    for (auto pair = line->rbegin(); pair != line->rend(); ++pair) {
      if (pair->first == key) return pair->second;
    }
  }
  return std::nullopt;
}

InputHold DataMetadata::input_hold(const std::string& input) const {
  std::optional<std::string> hold = get("input-hold");
  if (hold == "mixed") hold = get("input-hold." + input);
  return hold == to_string(InputHold::kZeroOrderHold) ? InputHold::kZeroOrderHold
                                                      : InputHold::kSample;
}

void DataMetadata::add_line(Line line) { lines_.push_back(std::move(line)); }

std::size_t DataMetadata::size() const {
  std::set<std::string> keys;
  for (const Line& line : lines_) {
    for (const auto& pair : line) keys.insert(pair.first);
  }
  return keys.size();
}

std::string DataMetadata::text() const {
  std::string out;
  for (const Line& line : lines_) {
    out += "# " + std::string(data::kMetadataTag);
    for (const auto& [key, value] : line) out += " " + key + "=" + value;
    out += "\n";
  }
  return out;
}

}  // namespace momentid
