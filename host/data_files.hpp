// Locating the data files shipped in data/ (piles, scenarios, machines). No path of the build is
// compiled in: the data is found beside the program that runs, so a build tree, an installed
// copy and a program embedding the library all find it the same way.
#pragma once
#include <string>
#include <vector>

namespace talus {

// the folders searched for data/'s files, in order: $TALUS_DATA_DIR if set; ./data; then, from
// the running program's folder up to the file system's root, the first folder's data/ that holds
// machines/ and scenarios/ (a build tree inside the repository: build/talus, build/tests/...)
// and share/talus/data/ (an installed prefix: bin/talus beside share/)
std::vector<std::string> data_search_paths();
// the path of data/<relative> in the first of data_search_paths() that has it; empty when none
std::string locate_data_file(const std::string& relative);
// the same, but throws InputError naming the places searched
std::string find_data_file(const std::string& relative);

}  // namespace talus
