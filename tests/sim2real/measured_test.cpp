// The measured-run format (sim2real/measured): a round trip, and every malformed field rejected
// with one error naming the file and the field (or line).
#include "sim2real/measured.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>

#include "host/error.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

namespace fs = std::filesystem;

MeasuredMetadata sample_metadata() {
  MeasuredMetadata m;
  m.scenario = "HD27";
  m.machine = "wa320";
  m.sample_rate_hz = test::kRefRateHz;
  m.pile_toe_x_m = 5.0;
  m.pile_scan = {{5.0, 0.0}, {6.0, 0.6}, {8.2, 2.0}, {10.1, 2.0}};
  m.drive = {{0.0, 0.0}, {0.8, 1.2}, {9.0, 0.0}};
  m.lift = {{0.0, 0.0}, {1.6, 0.2}};
  m.tilt = {{0.0, 0.0}};
  m.loaded_mass_kg = 2700.0;
  m.work_J = 127e3;
  return m;
}

// a complete measured run in a fresh folder: the reference series at 100 Hz, its summary, metadata
fs::path write_run(const std::string& tag) {
  const fs::path dir = test::fresh_temp_dir(tag);
  save_timeseries(dir / kTimeseriesFile, test::reference_series());
  RunSummary s;
  s.loaded_mass_kg = 2700.0;
  s.work_J = 127e3;
  s.scenario = "HD27";
  s.fidelity = "field";
  save_summary(dir / kSummaryFile, s);
  save_metadata(dir / kMetadataFile, sample_metadata());
  return dir;
}

// edits metadata.json with `change`, then returns the loader's error ("" when it loads)
template <class Change>
std::string error_after(const std::string& tag, Change change) {
  const fs::path dir = write_run(tag);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / kMetadataFile));
  change(j);
  std::ofstream(dir / kMetadataFile) << j.dump();
  try {
    load_measured_run(dir);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MeasuredRun, RoundTrip) {
  const fs::path dir = write_run("measured_round_trip");
  const MeasuredRun r = load_measured_run(dir);
  const MeasuredMetadata want = sample_metadata();
  EXPECT_EQ(r.meta.scenario, want.scenario);
  EXPECT_EQ(r.meta.machine, want.machine);
  EXPECT_EQ(r.meta.pile_scan, want.pile_scan);
  EXPECT_EQ(r.meta.drive, want.drive);
  EXPECT_EQ(r.meta.lift, want.lift);
  EXPECT_EQ(r.meta.tilt, want.tilt);
  EXPECT_DOUBLE_EQ(r.meta.loaded_mass_kg, 2700.0);
  EXPECT_EQ(r.run.series.size(), test::reference_series().size());
}

TEST(MeasuredRun, AFolderWithoutTheFilesSaysWhatAMeasuredRunHolds) {
  const fs::path dir = write_run("measured_missing_file");
  fs::remove(dir / kMetadataFile);
  try {
    load_measured_run(dir);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not a measured run: no metadata.json"), std::string::npos) << what;
    EXPECT_NE(what.find("docs/measured-data.md"), std::string::npos) << what;
  }
}

TEST(MeasuredRun, MalformedMetadataNamesFileAndField) {
  const std::vector<std::pair<std::string, std::function<void(nlohmann::json&)>>> cases = {
      {"'format'", [](nlohmann::json& j) { j["format"] = "csv"; }},
      {"'version'", [](nlohmann::json& j) { j["version"] = 2; }},
      {"'machine': missing", [](nlohmann::json& j) { j.erase("machine"); }},
      {"'sample_rate_hz'", [](nlohmann::json& j) { j["sample_rate_hz"] = -1; }},
      {"'pile_scan[2]': goes back", [](nlohmann::json& j) { j["pile_scan"][2][0] = 1.0; }},
      {"'operator_inputs.lift[1]': must be a pair",
       [](nlohmann::json& j) { j["operator_inputs"]["lift"][1] = "x"; }},
      {"'operator_inputs.tilt': missing",
       [](nlohmann::json& j) { j["operator_inputs"].erase("tilt"); }},
      {"'loaded_mass_kg': differs from summary.json",
       [](nlohmann::json& j) { j["loaded_mass_kg"] = 2600; }},
      {"'work_J': must be a finite number", [](nlohmann::json& j) { j["work_J"] = "lots"; }},
      {"'scenario': is 'FB35' but summary.json says 'HD27'",
       [](nlohmann::json& j) { j["scenario"] = "FB35"; }},
      // a toe far away ended in a misleading "needs more than 64 colours" (the scenarios' bound)
      {"'pile_toe_x_m': lies outside 0-100 m", [](nlohmann::json& j) { j["pile_toe_x_m"] = 1e12; }},
      // a target speed beyond any loader's: a unit error (mm/s), not an operator
      {"'operator_inputs.lift[1]': asks 200 m/s",
       [](nlohmann::json& j) { j["operator_inputs"]["lift"][1][1] = 200.0; }},
      {"'pile_toe_x_m': lies outside 0-100 m",
       [](nlohmann::json& j) { j["pile_toe_x_m"] = -50.0; }},
  };
  int k = 0;
  for (const auto& [expected, change] : cases) {
    const std::string e = error_after("measured_bad_" + std::to_string(k++), change);
    EXPECT_NE(e.find("metadata.json"), std::string::npos) << e;
    EXPECT_NE(e.find(expected), std::string::npos) << "expected '" << expected << "' in: " << e;
  }
}

// the time column sets the replay's duration: beyond a scenario's hour it is refused naming the
// file and field (a column to 1e7 s made diagnose simulate for hours)
TEST(MeasuredRun, ATimeColumnBeyondAnHourIsRefused) {
  const fs::path dir = write_run("measured_long");
  save_timeseries(dir / kTimeseriesFile, test::reference_series(test::kRefRateHz, 3600.0));
  try {
    load_measured_run(dir);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("timeseries.csv: field 't': runs from 3600"), std::string::npos) << m;
    EXPECT_NE(m.find("within 0-3600 s"), std::string::npos) << m;
  }
}

// the metrics compare samples one for one with the simulation's 100 Hz log: another rate is
// refused with the fix (a 1 Hz run scored a position error of 3.66 on noiseless data)
TEST(MeasuredRun, SampleRateIsTheContracts) {
  for (const double rate : {50.0, 1.0}) {
    const std::string e =
        error_after("measured_rate", [rate](nlohmann::json& j) { j["sample_rate_hz"] = rate; });
    EXPECT_NE(e.find("'sample_rate_hz'"), std::string::npos) << e;
    EXPECT_NE(e.find("resample the data to 100 Hz"), std::string::npos) << e;
  }
}

// each reading within what the record's machine can read (twice its data's largest,
// vehicle::reading_limits): a stroke in mm or a force a thousand times too large is named with its
// line, field, value and unit instead of being diagnosed as a strange machine
TEST(MeasuredRun, AReadingBeyondWhatTheMachineCanReadIsNamed) {
  for (const auto& [channel, value] : {std::pair<Channel, double>{Channel::d_lift, 850.0},
                                       std::pair<Channel, double>{Channel::f_lift, -2e9},
                                       std::pair<Channel, double>{Channel::v_drive, 40.0}}) {
    const fs::path dir = write_run("measured_beyond");
    TimeSeries series = test::reference_series();
    series[channel][7] = value;
    save_timeseries(dir / kTimeseriesFile, series);
    const std::string name = vehicle::kChannelNames[static_cast<std::size_t>(channel)];
    try {
      load_measured_run(dir);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("timeseries.csv: field '" + name + "' at t = 0.07 s is "), std::string::npos)
          << m;
      EXPECT_NE(m.find("that wa320 can read"), std::string::npos) << m;
    }
  }
  // the same record within the machine loads
  EXPECT_NO_THROW(load_measured_run(write_run("measured_within")));
}

// the load and the work within what the machine carries and does: a mass in grams or a work in
// mJ is named with the field and the unit to give
TEST(MeasuredRun, ALoadOrWorkBeyondTheMachineIsNamed) {
  const auto beyond = [](const std::string& tag, double mass, double work) {
    const fs::path dir = write_run(tag);
    RunSummary s;
    s.loaded_mass_kg = mass;
    s.work_J = work;
    s.scenario = "HD27";
    s.fidelity = "field";
    save_summary(dir / kSummaryFile, s);
    MeasuredMetadata m = sample_metadata();
    m.loaded_mass_kg = mass;
    m.work_J = work;
    save_metadata(dir / kMetadataFile, m);
    try {
      load_measured_run(dir);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string mass = beyond("measured_grams", 2.7e6, 127e3);
  EXPECT_NE(mass.find("metadata.json: field 'loaded_mass_kg': is 2.7e+06 kg, outside 0 to the"),
            std::string::npos)
      << mass;
  EXPECT_NE(mass.find("(give kg, not g)"), std::string::npos) << mass;
  const std::string work = beyond("measured_millijoules", 2700.0, 1.27e11);
  EXPECT_NE(work.find("metadata.json: field 'work_J': is 1.27e+11 J, beyond the"),
            std::string::npos)
      << work;
  EXPECT_NE(work.find("(give J, not mJ)"), std::string::npos) << work;
  const std::string machine =
      error_after("measured_no_machine", [](nlohmann::json& j) { j["machine"] = "wa999"; });
  EXPECT_NE(machine.find("field 'machine': names 'wa999'"), std::string::npos) << machine;
}

}  // namespace
}  // namespace talus::sim2real
