// Channel-contract CSV and summary.json: round trip, and malformed files rejected with a
// message that names file, line and field.
#include "sim2real/timeseries.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "host/error.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

namespace fs = std::filesystem;

const char* kHeader =
    "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,bucket_deg,pitch_deg,"
    "x_vehicle,bucket_tip_x,bucket_tip_z,power\n";

fs::path write_text(const fs::path& file, const std::string& text) {
  std::ofstream(file) << text;
  return file;
}

// the InputError message of loading `file`, or "" when it loads
std::string load_error(const fs::path& file) {
  try {
    load_timeseries(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(TimeseriesTest, RoundTripIsExact) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const TimeSeries s = test::simulated_series(100.0, 0.123456789);
  save_timeseries(dir / "x.csv", s);
  const TimeSeries back = load_timeseries(dir / "x.csv");
  ASSERT_EQ(back.size(), s.size());
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    EXPECT_EQ(back.columns[c], s.columns[c]) << kChannelNames[c];
  }
  // written through a temporary name that does not remain
  EXPECT_FALSE(fs::exists(dir / "x.csv.tmp"));
  fs::remove_all(dir);
}

TEST(TimeseriesTest, ColumnsInAnyOrderAndExtraColumnsIgnored) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const std::string row = "1,2,3,4,5,6,7,8,9,10,11,12,13";
  const fs::path f = write_text(dir / "x.csv",
                                "extra,power,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,"
                                "boom_deg,bucket_deg,pitch_deg,x_vehicle,bucket_tip_x,"
                                "bucket_tip_z,t\n"
                                "99," + row + ",0.00\n99," + row + ",0.01\n");
  const TimeSeries s = load_timeseries(f);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_DOUBLE_EQ(s[Channel::t][1], 0.01);
  EXPECT_DOUBLE_EQ(s[Channel::power][0], 1.0);
  EXPECT_DOUBLE_EQ(s[Channel::bucket_tip_z][0], 13.0);
  fs::remove_all(dir);
}

TEST(TimeseriesTest, MissingColumnNamesFileLineAndField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const fs::path f = write_text(dir / "x.csv",
                                "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,"
                                "bucket_deg,pitch_deg,x_vehicle,bucket_tip_x,power\n"
                                "0,1,2,3,4,5,6,7,8,9,10,11,12\n");
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string() + ":1:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'bucket_tip_z'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("missing column"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(TimeseriesTest, NanNamesFileLineAndField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const fs::path f = write_text(dir / "x.csv", std::string(kHeader) +
                                                   "0,1,2,3,4,5,6,7,8,9,10,11,12,13\n"
                                                   "0.01,1,nan,3,4,5,6,7,8,9,10,11,12,13\n");
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string() + ":3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'f_tilt'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a finite number"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(TimeseriesTest, NonNumericNamesFileLineAndField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const fs::path f = write_text(dir / "x.csv", std::string(kHeader) +
                                                   "0,1,2,3,4,5,6,7,8,9,10,11,12,13\n"
                                                   "0.01,1,2,3,4,5,6,7,8,9,10,11,12,13\n"
                                                   "0.02,1,2,3,4.5kN,5,6,7,8,9,10,11,12,13\n");
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string() + ":4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'v_drive'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'4.5kN' is not a number"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(TimeseriesTest, NonMonotonicTimeNamesFileLineAndField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  // a repeated time stamp is refused as well as one going backwards
  for (const char* bad : {"0.01", "0.005"}) {
    const fs::path f = write_text(dir / "x.csv",
                                  std::string(kHeader) + "0,1,2,3,4,5,6,7,8,9,10,11,12,13\n" +
                                      "0.01,1,2,3,4,5,6,7,8,9,10,11,12,13\n" + bad +
                                      ",1,2,3,4,5,6,7,8,9,10,11,12,13\n");
    const std::string msg = load_error(f);
    EXPECT_NE(msg.find(f.string() + ":4:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("field 't'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("does not increase"), std::string::npos) << msg;
  }
  fs::remove_all(dir);
}

TEST(TimeseriesTest, ShortRowNamesLine) {
  const fs::path dir = test::fresh_temp_dir("ts");
  const fs::path f = write_text(dir / "x.csv", std::string(kHeader) + "0,1,2\n");
  const std::string msg = load_error(f);
  EXPECT_NE(msg.find(f.string() + ":2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("has 3 fields"), std::string::npos) << msg;
  fs::remove_all(dir);
}

TEST(TimeseriesTest, SummaryRoundTripAndMissingField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  save_summary(dir / "s.json", test::reference_summary());
  const RunSummary s = load_summary(dir / "s.json");
  EXPECT_DOUBLE_EQ(s.loaded_mass_kg, test::kRefMassKg);
  EXPECT_DOUBLE_EQ(s.work_J, test::kRefWorkJ);
  EXPECT_EQ(s.scenario.value_or(""), "FB35");
  EXPECT_DOUBLE_EQ(s.dig_start_s.value_or(-1.0), test::kDigStart);
  EXPECT_DOUBLE_EQ(s.dig_end_s.value_or(-1.0), test::kDigEnd);

  write_text(dir / "bad.json", "{\"loaded_mass_kg\": 3460}");
  try {
    load_summary(dir / "bad.json");
    ADD_FAILURE() << "a summary without work_J loaded";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find((dir / "bad.json").string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("'work_J'"), std::string::npos) << msg;
  }
  write_text(dir / "bad.json", "{\"loaded_mass_kg\": \"heavy\", \"work_J\": 1}");
  EXPECT_THROW(load_summary(dir / "bad.json"), InputError);
  write_text(dir / "bad.json", "{\"loaded_mass_kg\": 1, \"work_J\": 1, \"dig_start_s\": 5, "
                               "\"dig_end_s\": 4}");
  EXPECT_THROW(load_summary(dir / "bad.json"), InputError);
  fs::remove_all(dir);
}

// a simulated run's summary carries more than the contract (particles, timing, coupling): the
// details are written beside the fields and read back as they stand, and a detail may not stand
// in for a field
TEST(TimeseriesTest, SummaryDetailsRoundTripAndCannotShadowAField) {
  const fs::path dir = test::fresh_temp_dir("ts");
  RunSummary s = test::reference_summary();
  s.details = {{"particles", 1234}, {"coupling", {{"max_passes", 3}}}, {"device", "pocl"}};
  save_summary(dir / "s.json", s);
  const RunSummary back = load_summary(dir / "s.json");
  EXPECT_EQ(back.details, s.details);
  EXPECT_DOUBLE_EQ(back.loaded_mass_kg, test::kRefMassKg);
  EXPECT_EQ(to_json(back), to_json(s));

  s.details["work_J"] = 1.0;
  EXPECT_THROW(to_json(s), Error);
  EXPECT_THROW(save_summary(dir / "t.json", s), Error);
  EXPECT_FALSE(fs::exists(dir / "t.json"));
  fs::remove_all(dir);
}

// the columns of logged samples and back, field for field
TEST(TimeseriesTest, SamplesAndColumnsConvertBothWays) {
  const TimeSeries series = test::reference_series();
  const TimeSeries back = to_timeseries(to_samples(series));
  for (std::size_t c = 0; c < kChannelCount; ++c) EXPECT_EQ(back.columns[c], series.columns[c]) << kChannelNames[c];
  TimeSeries ragged = series;
  ragged[Channel::power].pop_back();
  EXPECT_THROW(to_samples(ragged), Error);
}

TEST(TimeseriesTest, WindowAndLinearResampling) {
  // a 50 Hz series offset by 5 ms, resampled onto 100 Hz times: linear channels are exact
  const TimeSeries s = test::reference_series(50.0, 0.005);
  const TimeSeries w = select_window(test::reference_series(), 2.0, 8.0);
  EXPECT_EQ(w.size(), 601u);  // 2.00, 2.01, ..., 8.00 s
  EXPECT_DOUBLE_EQ(w[Channel::t].front(), 2.0);
  EXPECT_DOUBLE_EQ(w[Channel::t].back(), 8.0);
  const TimeSeries r = resample(s, w[Channel::t]);
  for (std::size_t n = 0; n < r.size(); ++n) {
    const double t = w[Channel::t][n];
    EXPECT_NEAR(r[Channel::f_lift][n], 50e3 + 5e3 * t, 1e-8);
    EXPECT_NEAR(r[Channel::bucket_tip_x][n], 0.1 * t, 1e-12);
  }
  // no extrapolation: a request before the first sample is an input error
  EXPECT_THROW(interpolate({0.0, 1.0}, {0.0, 1.0}, {-0.5}), InputError);
  EXPECT_DOUBLE_EQ(interpolate({0.0, 1.0}, {2.0, 4.0}, {0.25})[0], 2.5);
}

}  // namespace
}  // namespace talus::sim2real
