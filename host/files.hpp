// Writing files: every file goes to a temporary name first and is renamed into place, so an
// interrupted or failed run never leaves a half-written file behind nor clobbers an old one.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace talus {

// creates the folder (and parents) and checks a file can be written in it; InputError naming it
// when either is impossible
void make_output_dir(const std::string& dir);
// checks before any work that a file can be written at `path`: writes and removes an empty
// temporary file beside it; InputError naming `flag` and the path otherwise
void check_writable(const std::string& path, const std::string& flag);
// a temporary name next to `path`, unique to this process on this machine
std::string temporary_name(const std::string& path);
// renames the finished temporary file `tmp` to `path`; on failure removes it and throws Error
// naming `path` (writers that stream their own format, like PNG, end with this)
void move_into_place(const std::string& tmp, const std::string& path);
// writes `content` to a temporary name, then renames it to path
void write_file_atomically(const std::string& path, const std::string& content);
void write_json(const std::string& path, const nlohmann::json& j);
// the whole file's bytes; InputError naming the file when it cannot be read (`why_needed` says
// what it is for)
std::string read_file_bytes(const std::string& path, const std::string& why_needed);
// parses a JSON file; InputError naming the file when it cannot be opened (`why_needed` says
// what it is for) or is not JSON the parser accepts: bad syntax, or a number beyond double's
// range (nlohmann's out_of_range.406, which is not a parse_error: found by fuzzing, docs/
// reliability.md)
nlohmann::json read_json_file(const std::string& path, const std::string& why_needed);

// where talus keeps what it can rebuild (settled piles, program binaries): $TALUS_CACHE_DIR, else
// $XDG_CACHE_HOME/talus, else ~/.cache/talus (empty when none of them is set)
std::string default_cache_dir();

}  // namespace talus
