// Writing a whole text table at once, with errors that name the file.
#pragma once
#include <string>

namespace fountain {

// Writes text to path (replacing it); an InputError names the file if it cannot be opened or
// the write fails (a full disk shows at the flush or the close).
void write_text_file(const std::string& path, const std::string& text);

}  // namespace fountain
