#include "data/header.hpp"

#include <algorithm>
#include <map>
#include <string_view>

#include "data/format.hpp"
#include "data/text.hpp"

namespace momentid::data {
namespace {

// Splits the header row into names, taking the separator from it.
void read_names(const std::string& path, std::string_view line, Header& header) {
  header.separator = line.find(',') != std::string_view::npos   ? ','
                     : line.find(';') != std::string_view::npos ? ';'
                                                                : ' ';
  auto add = [&](std::size_t begin, std::size_t end) {
    std::string_view name = line.substr(begin, end - begin);
    const std::size_t leading = std::min(name.find_first_not_of(" \t"), name.size());
    name = trim(name);
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') {
      name = name.substr(1, name.size() - 2);
    }
    header.names.emplace_back(name);
    header.name_columns.push_back(begin + leading + 1);
  };
  if (header.separator == ' ') {
    std::size_t at = 0;
    for (;;) {
      while (at < line.size() && is_blank(line[at])) ++at;
      if (at == line.size()) break;
      std::size_t end = at;
      while (end < line.size() && !is_blank(line[end])) ++end;
      add(at, end);
      at = end;
    }
  } else {
    // The next separator outside double quotes: `"a[:, 0]"` is one name.
    const auto next_separator = [&](std::size_t from) {
      bool quoted = false;
      for (std::size_t i = from; i < line.size(); ++i) {
        if (line[i] == '"') quoted = !quoted;
        if (line[i] == header.separator && !quoted) return i;
      }
      return line.size();
    };
    std::size_t begin = 0;
    for (;;) {
      const std::size_t end = next_separator(begin);
      add(begin, end);
      if (end == line.size()) break;
      begin = end + 1;
    }
  }
  const bool all_numbers = std::all_of(header.names.begin(), header.names.end(), [](auto& n) {
    double value;
    return is_number(n, value);
  });
  if (all_numbers) {
    fail(text_location(path, header.line, 1, line),
         "expected a header row naming the columns, found a row of numbers");
  }
}

}  // namespace

bool is_time_name(std::string_view name) {
  std::string lower;
  for (char c : name) lower += static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  std::string_view rest = lower;
  if (rest.starts_with("time")) {
    rest.remove_prefix(4);
  } else if (rest.starts_with("t")) {
    rest.remove_prefix(1);
  } else {
    return false;
  }
  rest = trim(rest);
  if (rest.empty()) return true;
  // A unit: "[s]", "(ms)", ...
  return rest.size() >= 2 && ((rest.front() == '[' && rest.back() == ']') ||
                              (rest.front() == '(' && rest.back() == ')'));
}

Header read_header(const std::string& path, LineReader& lines, bool binary) {
  Header header;
  std::string_view line;
  std::string first_line;
  bool empty = true;
  while (lines.next(line)) {
    const long long number = lines.line_number();
    if (number == 1) {
      if (line.starts_with(kByteOrderMark)) line.remove_prefix(kByteOrderMark.size());
      first_line = line;
    }
    if (!line.empty() || number > 1) empty = false;
    const std::size_t start = line.find_first_not_of(" \t");
    if (start == std::string_view::npos) continue;
    if (line[start] == '#') {
      const std::size_t tag = line.find_first_not_of(" \t", start + 1);
      if (tag != std::string_view::npos && line.substr(tag).starts_with(kMetadataTag)) {
        DataMetadata::Line pairs =
            read_metadata_line(path, number, line, tag + kMetadataTag.size());
        if (!pairs.empty()) header.metadata.add_line(std::move(pairs));
      }
      continue;
    }
    if (const auto dt = header.metadata.get("dt")) {
      double value = 0;
      is_number(*dt, value);
      header.metadata_dt = value;
      header.metadata_dt_source = "dt=" + *dt + " in the metadata";
    }
    header.line = number;
    header.text = line;
    read_names(path, line, header);
    return header;
  }
  fail(text_location(path, 1, 1, first_line),
       empty && !binary ? "the file is empty: expected a header row naming the columns"
                        : "expected a header row naming the columns");
}

ColumnMap map_columns(const std::string& path, const Header& header, const ColumnRequest& request) {
  const auto location = [&](std::size_t column) {
    return text_location(path, header.line, column, header.text);
  };
  // The header's names for messages: the first twelve, each cut at 40 characters.
  std::string listed;
  for (std::size_t i = 0; i < header.names.size() && i < 12; ++i) {
    const std::string& name = header.names[i];
    listed += (listed.empty() ? "" : ", ") + name.substr(0, 40) + (name.size() > 40 ? "..." : "");
  }
  if (header.names.size() > 12) {
    listed += " and " + std::to_string(header.names.size() - 12) + " more";
  }
  const std::string known = header.names.empty() ? "the file has no " + header.item + "s"
                                                 : header.listing + ": " + listed;

  // The time column: the one `t` is renamed to, else `t`, else the first time-like name.
  std::string time_name;
  if (const auto renamed = request.rename.find("t"); renamed != request.rename.end()) {
    time_name = renamed->second;
    if (std::find(header.names.begin(), header.names.end(), time_name) == header.names.end()) {
      fail(location(1), "missing " + header.item + " '" + time_name + "' for 't' (" + known + ")");
    }
  } else if (std::find(header.names.begin(), header.names.end(), "t") != header.names.end()) {
    time_name = "t";
  } else {
    const auto found = std::find_if(header.names.begin(), header.names.end(), is_time_name);
    if (found != header.names.end()) time_name = *found;
  }
  if (request.dt) time_name.clear();

  std::vector<std::string> file_names;
  for (const std::string& name : request.names) {
    const auto renamed = request.rename.find(name);
    file_names.push_back(renamed == request.rename.end() ? name : renamed->second);
  }
  const auto matters = [&](const std::string& name) {
    return (!time_name.empty() && name == time_name) || name == "run" ||
           std::find(file_names.begin(), file_names.end(), name) != file_names.end();
  };

  ColumnMap map;
  map.output.assign(header.names.size(), -1);
  map.needed.assign(header.names.size(), 0);
  std::map<std::string_view, std::size_t> first;
  for (std::size_t i = 0; i < header.names.size(); ++i) {
    const std::string& name = header.names[i];
    const auto [seen, inserted] = first.emplace(name, i);
    if (!inserted && matters(name)) {
      fail(location(header.name_columns[i]),
           "column '" + name + "' appears twice in the header (first at column " +
               std::to_string(header.name_columns[seen->second]) + ")");
    }
  }
  if (const auto t = first.find(time_name); !time_name.empty() && t != first.end()) {
    map.time = static_cast<int>(t->second);
  }
  if (const auto r = first.find("run"); r != first.end()) map.run = static_cast<int>(r->second);
  if (map.time >= 0) map.needed[map.time] = 1;
  if (map.run >= 0) map.needed[map.run] = 1;

  for (std::size_t k = 0; k < request.names.size(); ++k) {
    const auto found = first.find(file_names[k]);
    if (found == first.end()) {
      const std::string& name = request.names[k];
      fail(location(1), "missing " + header.item + " '" + file_names[k] + "'" +
                            (file_names[k] == name ? "" : " for '" + name + "'") + " (" + known +
                            ")");
    }
    const std::size_t field = found->second;
    if (map.output[field] < 0) {
      map.output[field] = static_cast<int>(k);
      map.needed[field] = 1;
    } else {
      map.copies.emplace_back(k, static_cast<std::size_t>(map.output[field]));
    }
  }
  return map;
}

}  // namespace momentid::data
