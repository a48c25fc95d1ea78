#include "cooling/CoolingParams.hpp"

#include "params/ParameterFile.hpp"

namespace fountain {

std::string CoolingParams::tables() const {
  return table_directory.empty() ? std::string(FOUNTAIN_DATA_DIR) + "/cooling/sutherland_dopita_1993" : table_directory;
}

CoolingParams CoolingParams::from(const ParameterFile& p) {
  CoolingParams c;
  c.enabled = p.flag("cooling.enabled");
  c.metallicity = p.text("cooling.metallicity");
  c.table_directory = p.text("cooling.table_directory");
  c.hydrogen_fraction = p.real("cooling.hydrogen_fraction");
  return c;
}

}  // namespace fountain
