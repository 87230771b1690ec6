// Test helper: an environment variable set for a scope, the old value put back after it.
#pragma once
#include <cstdlib>
#include <optional>
#include <string>

namespace talus::test {

class ScopedEnv {
 public:
  // value nullptr: the variable unset for the scope
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      setenv(name, value, 1);
    else
      unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

}  // namespace talus::test
