#include "sim2real/measured.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "host/error.hpp"
#include "host/files.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/machine.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::sim2real {

namespace fs = std::filesystem;

namespace {

// relative agreement asked of values that appear in two files (metadata and summary)
constexpr double kSameValue = 1e-9;
// the time column may step off the stated rate by this fraction of a period (CSV rounding)
constexpr double kPeriodTolerance = 1e-6;

// reads one JSON object, or InputError naming the file
nlohmann::json read_object(const fs::path& file) {
  const nlohmann::json j =
      read_json_file(file.string(), std::string("a measured run needs ") + kMetadataFile);
  if (!j.is_object()) throw InputError(file.string() + ": must be a JSON object");
  return j;
}

// the field checks, each naming file and field
struct Fields {
  const fs::path& file;
  const nlohmann::json& j;

  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw InputError(file.string() + ": field '" + field + "': " + problem);
  }
  const nlohmann::json& member(const nlohmann::json& o, const std::string& field, const std::string& key) const {
    if (!o.contains(key)) fail(field, "missing");
    return o.at(key);
  }
  double number(const nlohmann::json& o, const std::string& field, const std::string& key) const {
    const auto& v = member(o, field, key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(field, "must be a finite number, got " + v.dump());
    return v.get<double>();
  }
  std::string text(const nlohmann::json& o, const std::string& field, const std::string& key) const {
    const auto& v = member(o, field, key);
    if (!v.is_string() || v.get<std::string>().empty()) fail(field, "must be a non-empty string, got " + v.dump());
    return v.get<std::string>();
  }
  // [[a, b], ...] of finite numbers with a increasing (strictly when `strict`)
  Series2 pairs(const nlohmann::json& o, const std::string& field, const std::string& key, bool strict) const {
    const auto& v = member(o, field, key);
    if (!v.is_array() || v.empty()) fail(field, "must be a non-empty array of [a, b] pairs");
    Series2 out;
    for (size_t i = 0; i < v.size(); ++i) {
      const std::string where = field + "[" + std::to_string(i) + "]";
      const auto& p = v[i];
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number() ||
          !std::isfinite(p[0].get<double>()) || !std::isfinite(p[1].get<double>()))
        fail(where, "must be a pair of finite numbers, got " + p.dump());
      const double a = p[0].get<double>();
      if (!out.empty() && (strict ? a <= out.back().first : a < out.back().first))
        fail(where, "goes back; sort the pairs by their first value");
      out.emplace_back(a, p[1].get<double>());
    }
    return out;
  }
};

bool same(double a, double b) { return std::abs(a - b) <= kSameValue * std::max(std::abs(a), std::abs(b)); }

// a record's readings and scalars within what its machine can read, carry and do: a stroke in mm,
// a force in mN or a mass in grams would otherwise pass as a strange machine and the diagnosis
// would fit effects to a unit error (a unit too large a thousandfold reads too small, which no
// bound can tell from a light dig)
void check_within_machine(const MeasuredRun& r, const fs::path& dir, const Fields& f) {
  const std::string machine = vehicle::find_data_file(r.meta.machine, "machines");
  if (machine.empty())
    f.fail("machine", "names '" + r.meta.machine + "', which is neither a file nor data/machines/" +
                          r.meta.machine + ".json");
  const vehicle::WheelLoader loader(machine);
  const auto limit = vehicle::reading_limits(loader);
  const std::string csv = (dir / kTimeseriesFile).string();
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    if (limit[c] == 0.0) continue;
    const vehicle::SensorChannel& ch = vehicle::kSensorChannels[c];
    const std::vector<double>& column = r.run.series.columns[c];
    for (std::size_t k = 0; k < column.size(); ++k) {
      const double v = column[k];
      if (std::abs(v) <= limit[c]) continue;
      // a thousand times too large is a prefix's worth: say which
      const std::string hint = std::abs(v) <= 1e3 * limit[c]
                                   ? "; a thousand times too large: is the column in another unit?"
                                   : "";
      // named by the sample's time: the reader skips blank lines, so a line number could be off
      throw InputError(
          csv + ": field '" + ch.name + "' at t = " + message_number(r.run.series[Channel::t][k]) +
          " s is " + message_number(v) + " " + ch.unit + ", beyond the " +
          message_number(limit[c]) + " " + ch.unit + " that " + loader.name() +
          " can read (five times its machine data's largest); give it in " + ch.unit + hint);
    }
  }
  // the load: at most what tips the empty machine with its boom low (the most it can carry)
  const double tipping = loader.static_tipping_load();
  if (!(r.meta.loaded_mass_kg >= 0.0 && r.meta.loaded_mass_kg <= tipping))
    f.fail("loaded_mass_kg", "is " + message_number(r.meta.loaded_mass_kg) +
                                 " kg, outside 0 to the " + message_number(tipping) +
                                 " kg that tips " + loader.name() + " (give kg, not g)");
  // the work: at most the largest power over the whole record
  const auto& t = r.run.series[Channel::t];
  const double duration = t.empty() ? 0.0 : t.back() - t.front();
  const double most = limit[static_cast<std::size_t>(Channel::power)] * duration;
  if (!(std::abs(r.meta.work_J) <= most))
    f.fail("work_J", "is " + message_number(r.meta.work_J) + " J, beyond the " +
                         message_number(most) + " J that " + loader.name() + " can do in the " +
                         message_number(duration) + " s of the record (give J, not mJ)");
}

}  // namespace

MeasuredMetadata load_metadata(const fs::path& file) {
  const nlohmann::json j = read_object(file);
  const Fields f{file, j};
  // format and version first: anything else is someone else's file
  if (f.text(j, "format", "format") != kMeasuredFormat)
    f.fail("format", std::string("must be \"") + kMeasuredFormat + "\"");
  const double version = f.number(j, "version", "version");
  if (version != kMeasuredVersion)
    f.fail("version", "is " + std::to_string(version) + "; this talus reads version " + std::to_string(kMeasuredVersion));
  MeasuredMetadata m;
  m.scenario = f.text(j, "scenario", "scenario");
  m.machine = f.text(j, "machine", "machine");
  m.sample_rate_hz = f.number(j, "sample_rate_hz", "sample_rate_hz");
  // the channel contract's rate: the metrics compare the simulation's 100 Hz samples with these
  // one for one (a 1 Hz run gave a position error of 3.66 on noiseless data)
  if (m.sample_rate_hz != kContractRateHz)
    f.fail("sample_rate_hz", "is " + message_number(m.sample_rate_hz) +
                                 "; the channel contract is 100 Hz: resample the data to 100 Hz");
  m.pile_toe_x_m = f.number(j, "pile_toe_x_m", "pile_toe_x_m");
  if (!(m.pile_toe_x_m >= 0.0 && m.pile_toe_x_m <= vehicle::kMaxPileToeX))
    f.fail("pile_toe_x_m", "lies outside 0-" + message_number(vehicle::kMaxPileToeX) +
                               " m from the machine's start (front axle at x = 0)");
  m.pile_scan = f.pairs(j, "pile_scan", "pile_scan", false);
  const auto& inputs = f.member(j, "operator_inputs", "operator_inputs");
  if (!inputs.is_object()) f.fail("operator_inputs", "must be an object with drive, lift and tilt series");
  m.drive = f.pairs(inputs, "operator_inputs.drive", "drive", false);
  m.lift = f.pairs(inputs, "operator_inputs.lift", "lift", false);
  m.tilt = f.pairs(inputs, "operator_inputs.tilt", "tilt", false);
  // the target speeds within what any loader reaches, as a scenario's (vehicle/machine.hpp)
  const auto within = [&](const Series2& v, const std::string& field, double fastest) {
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!(std::abs(v[i].second) <= fastest))
        f.fail(field + "[" + std::to_string(i) + "]", "asks " + message_number(v[i].second) +
                                                          " m/s; give a target speed within +-" +
                                                          message_number(fastest) + " m/s");
  };
  within(m.drive, "operator_inputs.drive", vehicle::kMaxDriveSpeed);
  within(m.lift, "operator_inputs.lift", vehicle::kMaxCylinderSpeed);
  within(m.tilt, "operator_inputs.tilt", vehicle::kMaxCylinderSpeed);
  m.loaded_mass_kg = f.number(j, "loaded_mass_kg", "loaded_mass_kg");
  m.work_J = f.number(j, "work_J", "work_J");
  if (!(m.loaded_mass_kg >= 0.0)) f.fail("loaded_mass_kg", "must not be negative");
  return m;
}

void save_metadata(const fs::path& file, const MeasuredMetadata& m) {
  auto pairs = [](const Series2& s) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& [x, y] : s) a.push_back({x, y});
    return a;
  };
  nlohmann::json j = {{"format", kMeasuredFormat},
                      {"version", kMeasuredVersion},
                      {"scenario", m.scenario},
                      {"machine", m.machine},
                      {"sample_rate_hz", m.sample_rate_hz},
                      {"pile_toe_x_m", m.pile_toe_x_m},
                      {"pile_scan", pairs(m.pile_scan)},
                      {"operator_inputs", {{"drive", pairs(m.drive)}, {"lift", pairs(m.lift)}, {"tilt", pairs(m.tilt)}}},
                      {"loaded_mass_kg", m.loaded_mass_kg},
                      {"work_J", m.work_J}};
  write_file_atomically(file.string(), j.dump(1) + "\n");
}

MeasuredRun load_measured_run(const fs::path& dir) {
  // a folder that is not a measured run at all: say what one holds
  for (const char* file : {kTimeseriesFile, kSummaryFile, kMetadataFile})
    if (!fs::exists(dir / file))
      throw InputError(dir.string() + ": not a measured run: no " + file + "; a measured run folder holds " +
                       kTimeseriesFile + ", " + kSummaryFile + " and " + kMetadataFile + " (docs/measured-data.md; " +
                       "talus synth writes one)");
  MeasuredRun r;
  r.run = load_run(dir);
  const fs::path file = dir / kMetadataFile;
  r.meta = load_metadata(file);
  const nlohmann::json none;
  const Fields f{file, none};
  // the time column at the stated rate, within a scenario's longest duration (it sets the replay's)
  const auto& t = r.run.series[Channel::t];
  if (!t.empty() && !(t.front() >= 0.0 && t.back() <= vehicle::kMaxScenarioDuration))
    throw InputError((dir / kTimeseriesFile).string() + ": field 't': runs from " +
                     message_number(t.front()) + " to " + message_number(t.back()) +
                     " s; a measured run lies within 0-" +
                     message_number(vehicle::kMaxScenarioDuration) +
                     " s from its start (split longer records into runs, each timed from 0)");
  const double period = 1.0 / r.meta.sample_rate_hz;
  for (size_t k = 1; k < t.size(); ++k) {
    if (std::abs(t[k] - t[k - 1] - period) > kPeriodTolerance * period)
      throw InputError((dir / kTimeseriesFile).string() + ": line " + std::to_string(k + 2) + ": field 't': steps " +
                       std::to_string(t[k] - t[k - 1]) + " s, not the metadata's 1/" +
                       std::to_string(r.meta.sample_rate_hz) + " s; resample or fix sample_rate_hz");
  }
  // the scalars the summary repeats must agree
  if (!same(r.meta.loaded_mass_kg, r.run.summary.loaded_mass_kg))
    f.fail("loaded_mass_kg", "differs from summary.json's; the two files must describe the same run");
  if (!same(r.meta.work_J, r.run.summary.work_J))
    f.fail("work_J", "differs from summary.json's; the two files must describe the same run");
  if (r.run.summary.scenario && *r.run.summary.scenario != r.meta.scenario)
    f.fail("scenario", "is '" + r.meta.scenario + "' but summary.json says '" + *r.run.summary.scenario + "'");
  check_within_machine(r, dir, f);
  return r;
}

}  // namespace talus::sim2real
