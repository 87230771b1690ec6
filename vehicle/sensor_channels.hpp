// The run contract's sensor channels (SPEC §2.4, paper Table 1), defined once, beside the sensors
// that produce them: the sample a step's sensors read, and the table that names each channel of
// timeseries.csv, in file order, with the sample's field that carries it and its unit. The CSV
// writer (vehicle/sensors), the run files (sim2real/timeseries), replay and the effects all read
// this table; nothing else spells the channel list.
// Conventions: forces in N (cylinder: positive pushes it longer; traction: positive forward on the
// machine), lengths in m, angles in degrees positive nose-up / boom-up / bucket-curled, measured in
// the front frame's x-z plane; d_lift and d_tilt are strokes (pin-to-pin length minus closed length),
// d_lift the mean of the two lift cylinders and f_lift their sum.
#pragma once
#include <array>
#include <cstddef>
#include <string>
#include <string_view>

namespace talus::vehicle {

struct SensorSample {
  double t = 0.0;
  double f_lift = 0.0, f_tilt = 0.0, f_traction = 0.0;
  double v_drive = 0.0;
  double d_lift = 0.0, d_tilt = 0.0;
  double boom_deg = 0.0, bucket_deg = 0.0, pitch_deg = 0.0;
  double x_vehicle = 0.0;
  double bucket_tip_x = 0.0, bucket_tip_z = 0.0;
  double power = 0.0;
  double lift_rate = 0.0, tilt_rate = 0.0;  // ḋ_l, ḋ_t [m/s] (not in the CSV contract)
};

// one column of timeseries.csv
struct SensorChannel {
  const char* name;             // the CSV header's name
  double SensorSample::*field;  // where a sample carries it
  const char* unit;             // SI
};

// the contract, in file order
inline constexpr std::array<SensorChannel, 14> kSensorChannels = {{
    {"t", &SensorSample::t, "s"},
    {"f_lift", &SensorSample::f_lift, "N"},
    {"f_tilt", &SensorSample::f_tilt, "N"},
    {"f_traction", &SensorSample::f_traction, "N"},
    {"v_drive", &SensorSample::v_drive, "m/s"},
    {"d_lift", &SensorSample::d_lift, "m"},
    {"d_tilt", &SensorSample::d_tilt, "m"},
    {"boom_deg", &SensorSample::boom_deg, "deg"},
    {"bucket_deg", &SensorSample::bucket_deg, "deg"},
    {"pitch_deg", &SensorSample::pitch_deg, "deg"},
    {"x_vehicle", &SensorSample::x_vehicle, "m"},
    {"bucket_tip_x", &SensorSample::bucket_tip_x, "m"},
    {"bucket_tip_z", &SensorSample::bucket_tip_z, "m"},
    {"power", &SensorSample::power, "W"},
}};
inline constexpr std::size_t kChannelCount = kSensorChannels.size();

// the channels by name in code (ts[Channel::f_lift]); each enumerator is its column's index, which
// the static_asserts below hold to the table
enum class Channel : std::size_t {
  t, f_lift, f_tilt, f_traction, v_drive, d_lift, d_tilt, boom_deg, bucket_deg, pitch_deg,
  x_vehicle, bucket_tip_x, bucket_tip_z, power
};

// the header's names alone, in file order
inline constexpr std::array<const char*, kChannelCount> kChannelNames = [] {
  std::array<const char*, kChannelCount> names{};
  for (std::size_t c = 0; c < kChannelCount; ++c) names[c] = kSensorChannels[c].name;
  return names;
}();

// the header line of timeseries.csv: every channel's name, comma-separated, in file order
inline std::string channel_header() {
  std::string header;
  for (const SensorChannel& c : kSensorChannels) header += (header.empty() ? "" : ",") + std::string(c.name);
  return header;
}

// the enumerator and the table name the same column
constexpr bool names_column(Channel c, std::string_view name) {
  return std::string_view(kSensorChannels[static_cast<std::size_t>(c)].name) == name;
}
static_assert(names_column(Channel::t, "t") && names_column(Channel::f_lift, "f_lift") &&
              names_column(Channel::f_tilt, "f_tilt") && names_column(Channel::f_traction, "f_traction") &&
              names_column(Channel::v_drive, "v_drive") && names_column(Channel::d_lift, "d_lift") &&
              names_column(Channel::d_tilt, "d_tilt") && names_column(Channel::boom_deg, "boom_deg") &&
              names_column(Channel::bucket_deg, "bucket_deg") && names_column(Channel::pitch_deg, "pitch_deg") &&
              names_column(Channel::x_vehicle, "x_vehicle") &&
              names_column(Channel::bucket_tip_x, "bucket_tip_x") &&
              names_column(Channel::bucket_tip_z, "bucket_tip_z") && names_column(Channel::power, "power"));
static_assert(static_cast<std::size_t>(Channel::power) + 1 == kChannelCount, "one enumerator per column");

}  // namespace talus::vehicle
