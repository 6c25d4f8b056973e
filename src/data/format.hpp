#pragma once
// The fixed parts of momentid's own data layouts (docs/data-files.md), in one place for the
// readers and the writer: the binary magic, the metadata tag, and the header text.

#include <string>
#include <string_view>
#include <vector>

#include "momentid/metadata.hpp"

namespace momentid::data {

// The first bytes of a binary data file.
inline constexpr std::string_view kMagic = "MOMNTID1";
// A comment line `# momentid: ...` holds metadata pairs.
inline constexpr std::string_view kMetadataTag = "momentid:";
inline constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

// Reads the `key=value` pairs of metadata line `line_number`, which start at byte `pairs`.
// Throws DataError at a pair without '=' or a `dt` that is not a positive number.
DataMetadata::Line read_metadata_line(const std::string& path, long long line_number,
                                      std::string_view line, std::size_t pairs);

// The header text of a data file: the metadata lines, then the column names separated by
// commas, then a newline. A binary file holds the same text after its magic and length.
std::string header_text(const DataMetadata& metadata, const std::vector<std::string>& columns);

}  // namespace momentid::data
