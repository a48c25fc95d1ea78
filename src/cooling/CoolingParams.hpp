// Radiative cooling settings of a run: on or off, the tables' composition and where they are.
#pragma once
#include <string>

namespace fountain {

class ParameterFile;

struct CoolingParams {
  bool enabled = false;
  std::string metallicity = "primordial";  // "primordial" or [Fe/H] in [-3, 0.5]
  std::string table_directory;             // the SD93 .cie files; empty: the copy shipped in data/
  double hydrogen_fraction = 0.76;

  // The folder the tables are read from.
  std::string tables() const;

  static CoolingParams from(const ParameterFile& p);
};

}  // namespace fountain
