// Saved states (issue 16): the envelope of a simulation's state file, which the embedding facade
// (embed/talus.cpp) writes and reads; the state inside is DiggingSimulation::save_state's, a
// loading cycle's or the machine alone's.
//
// The file (version kStateFormatVersion, little-endian whatever the machine, host/binary.hpp):
//   "TALUSSTA" (8 bytes), u32 version, then the strings key, commit and device, the payload's
//   length and bytes, then u64 FNV-1a of every byte before it.
// The key says what made the simulation, one "name=value" line each (scenario and machine files
// by content, level, seed, loading-cycle options, particle count): a state is restored only into
// a simulation with the same key, since the constructor's configuration is not in the payload.
// commit and device are recorded: bit-identical continuation holds on the same build and device
// (work-group size included); on another the state restores and steps on, to float rounding.
#pragma once
#include <cstdint>
#include <string>

#include "host/binary.hpp"

namespace talus {

// the file's format: raise it whenever what any save_state writes changes (a file of another
// version is refused, never half-read)
// 2: walls, type G (2026-11-25); 3: the dig's sweep count (2026-11-27); 4: the particle
// contacts' colours (2026-11-27, issue 13); 5: type G's full particle diameters (growth) and the
// aggregate log's principal axes (2026-11-29, issue 14); 6: type G's bucket content a body by
// default, a machine of one more body (2026-11-29, issue 14: a version-5 type-G state would meet
// a machine it does not fit); 7: type G's terrain support under the bucket by default (one more
// machine constraint), the aggregate log's support force, held mass, soil force and particle
// force, type D's soil force log (2026-11-29, issue 14); 8: the aggregate log's terrain force,
// interface B's whole force on the aggregate, and its zone's particles' mean velocity (2026-11-30,
// issue 14); 9: type D's soil force log split by the bucket's faces (2026-11-30, issue 14); 10:
// type G's resting load riding with the bucket (its study option, and with it on each particle's
// rest and the bucket's last motion; 2026-12-01, issue 14)
inline constexpr std::uint32_t kStateFormatVersion = 10;

struct SavedStateHeader {
  std::string key;     // "name=value" lines: what the simulation was made from
  std::string commit;  // the build's git commit
  std::string device;  // the OpenCL device the particles ran on (empty for the machine alone)
};

// the file's bytes for a payload
std::string seal_state(const SavedStateHeader& header, const std::string& payload);
// the header of a state file's bytes, its payload in *payload; InputError naming `where` (the
// file) for another magic or version, a short file or a wrong checksum
SavedStateHeader open_state(const std::string& bytes, const std::string& where,
                            std::string* payload);
// a reader over a payload from open_state, naming `where` and what to do about a bad file
ByteReader payload_reader(const std::string& payload, const std::string& where);
// where two keys differ, for an error: "level=D200 (saved) against level=D400 (this
// simulation)"; empty when they are the same
std::string key_difference(const std::string& saved, const std::string& mine);

}  // namespace talus
