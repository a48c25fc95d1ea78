#include "app/TextFile.hpp"

#include <fmt/format.h>

#include <cstdio>

#include "core/Error.hpp"

namespace fountain {

void write_text_file(const std::string& path, const std::string& text) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw InputError(fmt::format("{}: cannot be written", path));
  const bool written = std::fputs(text.c_str(), out) >= 0 && std::fflush(out) == 0;
  if (std::fclose(out) != 0 || !written) throw InputError(fmt::format("{}: writing failed (disk full?)", path));
}

}  // namespace fountain
