// Running the built `talus` tool from a test: exit code and stderr of one command line.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace talus::test {

inline const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";

struct Outcome {
  int code;         // exit code; -1 when the tool did not exit normally
  std::string err;  // what it wrote on stderr
};

// runs the tool through the shell with `env` prefixed (may be empty), stdout discarded
inline Outcome run_talus(const std::string& env, const std::string& args) {
  const auto err_path = std::filesystem::temp_directory_path() /
                        ("talus_cli_stderr_" + std::to_string(::getpid()) + ".txt");
  const std::string cmd = env + " " + kTalus + " " + args + " >/dev/null 2>" + err_path.string();
  const int status = std::system(cmd.c_str());
  std::ifstream in(err_path);
  std::stringstream ss;
  ss << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

}  // namespace talus::test
