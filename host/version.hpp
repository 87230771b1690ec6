// The build's provenance, for summaries that must say which talus made them (issue 15): the
// version of the project (CMakeLists.txt) and the git commit of the source tree at build time
// (`git describe --always --dirty`, "unknown" outside a git checkout). Generated at every build
// by cmake/version.cmake.
#pragma once

namespace talus {

const char* talus_version();
const char* git_commit();

}  // namespace talus
