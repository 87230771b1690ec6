// Saved states, first part (issue 16): settled piles kept on disk and found again by what made
// them. A pile takes from a second (D400) to most of an hour (D100) to fill and settle, and every
// run, sweep sample and MPI rank of the same scenario and level settles the same one.
//
// The file (version kPileFormatVersion, little-endian whatever the machine):
//   "TALUSPIL" (8 bytes), u32 version, u64 length + the key's canonical bytes (pile_key_bytes),
//   the recorded numbers, the bounds, the geoms, the particles' arrays (positions, velocities,
//   angular velocities, rotations, radii, inverse masses, inverse inertias), then u64 FNV-1a of
//   every byte before it. Doubles are written bit for bit, so a pile read back is the pile written.
// read_pile throws InputError naming the file for another magic or version, a short file or a
// wrong checksum; the cache (build_pile_cached) treats those as a miss with a note, builds the
// pile again and replaces the file.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "host/device.hpp"
#include "host/files.hpp"
#include "host/progress.hpp"
#include "terrain/pile.hpp"

namespace talus {

// the file's format: raise it whenever what is written changes (a file of another version is
// refused, never half-read)
inline constexpr std::uint32_t kPileFormatVersion = 1;

// the pile as the file's bytes, under `key` (pile_key_bytes), and back; parse_pile throws
// InputError naming `where` (the file) when the bytes are not such a file, and stores the key
// in *key when given
std::string serialise_pile(const PileBuild& pile, const std::string& key);
PileBuild parse_pile(const std::string& bytes, const std::string& where,
                     std::string* key = nullptr);
// the same through a file (written atomically: temporary name, then rename)
void write_pile(const std::string& path, const PileBuild& pile, const std::string& key);
PileBuild read_pile(const std::string& path, std::string* key = nullptr);

// everything that decides a settled pile, as canonical bytes: the placed profile's content (its
// points, width and rear wall; not its name or path), the level (name, D, dt, sweeps), every
// field of the material and of the build's options (the seed among them), the OpenCL device's
// description and the build's git commit. Doubles enter bit for bit, strings with their length
std::string pile_key_bytes(const PileProfile& profile, const FidelityPreset& preset,
                           const Material& material, const PileBuildOptions& options,
                           const std::string& device, const std::string& commit);
// the key's file name stem: the hash as 16 hex digits
std::string pile_key_name(const std::string& key_bytes);

struct PileCacheOptions {
  bool enabled = false;  // off unless a caller asks (the CLI and the facade do, by default)
  std::string dir;       // empty: default_cache_dir() (host/files.hpp), the piles under piles/
  std::string commit;    // empty: the build's (git_commit()); one ending in "-dirty" is not cached
  // what the cache tells a person (a hit, a miss it fills, why it is not used, a file it cannot
  // write): one line each; none given, nothing is told
  std::function<void(const std::string&)> note;
};

// build_pile, through the cache when options.enabled: a pile saved under the same key is read
// back (PileBuild::from_cache set), otherwise it is built and saved. A missing, unreadable,
// corrupt or other-version file is a miss; a folder that cannot be written is a note, and the
// pile is built all the same
PileBuild build_pile_cached(Device& dev, const PileProfile& profile, const FidelityPreset& preset,
                            const Material& material, const PileBuildOptions& options,
                            const PileCacheOptions& cache, Progress* progress);

}  // namespace talus
