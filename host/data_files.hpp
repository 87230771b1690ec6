// Locating the data files shipped in data/ (piles, scenarios, machines).
#pragma once
#include <string>

namespace talus {

// the path of data/<relative>: TALUS_DATA_DIR if set, then ./data, then the source tree's data/;
// empty when none has it
std::string locate_data_file(const std::string& relative);
// the same, but throws InputError naming the places searched
std::string find_data_file(const std::string& relative);

}  // namespace talus
