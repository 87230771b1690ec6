#include "sim2real/timeseries.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "host/error.hpp"
#include "host/files.hpp"
#include "vehicle/sensors.hpp"

namespace talus::sim2real {

namespace fs = std::filesystem;

namespace {

// digits that round-trip a double exactly (std::numeric_limits<double>::max_digits10)
constexpr int kRoundTripDigits = 17;
// summary.json's fields that RunSummary holds by name; any other key is a detail
constexpr const char* kSummaryFields[] = {"loaded_mass_kg", "work_J", "scenario", "fidelity", "dig_start_s", "dig_end_s"};

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  // a trailing comma means one more (empty) field
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

[[noreturn]] void fail(const fs::path& file, std::size_t line, const std::string& field,
                       const std::string& problem) {
  std::ostringstream msg;
  msg << file.string() << ":" << line << ": field '" << field << "': " << problem;
  throw InputError(msg.str());
}

// a strict number: the whole cell must parse, and NaN or infinity are refused
double parse_number(const std::string& cell, const fs::path& file, std::size_t line,
                    const std::string& field) {
  if (cell.empty()) fail(file, line, field, "empty cell; every sample needs a number");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size()) {
    fail(file, line, field, "'" + cell + "' is not a number");
  }
  if (!std::isfinite(v) || errno == ERANGE) {
    fail(file, line, field,
         "'" + cell + "' is not a finite number (NaN, infinity or out of range); "
         "fill or drop the sample");
  }
  return v;
}

std::string format_number(double v) {
  std::ostringstream out;
  out.precision(kRoundTripDigits);
  out << v;
  return out.str();
}

}  // namespace

std::string Run::label() const {
  if (summary.scenario && summary.fidelity) return *summary.scenario + "-" + *summary.fidelity;
  const fs::path normal = dir.lexically_normal();
  const std::string name = normal.filename().empty() ? normal.parent_path().filename().string()
                                                     : normal.filename().string();
  return name.empty() ? dir.string() : name;
}

TimeSeries load_timeseries(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open the time-series file");

  // header: map each contract channel to its column index
  std::string line;
  std::size_t line_no = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++line_no;
    if (!trim(line).empty()) {
      header = split_csv_line(line);
      break;
    }
  }
  if (header.empty()) fail(file, line_no == 0 ? 1 : line_no, "header", "the file is empty");
  std::array<std::size_t, kChannelCount> index{};
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    std::size_t found = header.size();
    for (std::size_t k = 0; k < header.size(); ++k) {
      if (header[k] == kChannelNames[c]) {
        if (found != header.size()) fail(file, line_no, kChannelNames[c], "duplicate column");
        found = k;
      }
    }
    if (found == header.size()) {
      fail(file, line_no, kChannelNames[c],
           "missing column; the header must name every channel of the contract (" + vehicle::channel_header() + ")");
    }
    index[c] = found;
  }

  // rows: every cell a finite number, time strictly increasing
  TimeSeries series;
  const std::size_t t_col = static_cast<std::size_t>(Channel::t);
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != header.size()) {
      fail(file, line_no, "row",
           "has " + std::to_string(cells.size()) + " fields, the header has " +
               std::to_string(header.size()));
    }
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      series.columns[c].push_back(parse_number(cells[index[c]], file, line_no, kChannelNames[c]));
    }
    const auto& t = series.columns[t_col];
    if (t.size() > 1 && !(t.back() > t[t.size() - 2])) {
      fail(file, line_no, "t",
           "time " + format_number(t.back()) + " s does not increase (previous sample " +
               format_number(t[t.size() - 2]) + " s); samples must be in strictly increasing time");
    }
  }
  if (series.size() < 2) {
    fail(file, line_no, "t", "fewer than two samples; a time series needs at least two");
  }
  return series;
}

TimeSeries to_timeseries(const std::vector<vehicle::SensorSample>& samples) {
  TimeSeries ts;
  for (auto& column : ts.columns) column.reserve(samples.size());
  for (const auto& s : samples) {
    for (size_t c = 0; c < kChannelCount; ++c) ts.columns[c].push_back(s.*vehicle::kSensorChannels[c].field);
  }
  return ts;
}

std::vector<vehicle::SensorSample> to_samples(const TimeSeries& series) {
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    if (series.columns[c].size() != series.size()) {
      throw Error("time series: channel '" + std::string(kChannelNames[c]) + "' has a different length from t");
    }
  }
  std::vector<vehicle::SensorSample> samples(series.size());
  for (std::size_t n = 0; n < series.size(); ++n) {
    for (std::size_t c = 0; c < kChannelCount; ++c) samples[n].*vehicle::kSensorChannels[c].field = series.columns[c][n];
  }
  return samples;
}

void save_timeseries(const fs::path& file, const TimeSeries& series) {
  // the sensors' own writer, so simulated and converted runs are written alike
  write_file_atomically(file, vehicle::sensor_csv(to_samples(series)));
}

RunSummary load_summary(const fs::path& file) {
  const nlohmann::json j = read_json_file(
      file.string(),
      "the run summary; summary.json is written last, so a folder without it holds a run that did "
      "not finish: rerun it");
  if (!j.is_object()) throw InputError(file.string() + ": the summary must be a JSON object");

  // numbers: required ones must exist; all must be finite
  auto number = [&](const char* key, bool required) -> std::optional<double> {
    if (!j.contains(key)) {
      if (required) {
        throw InputError(file.string() + ": field '" + key + "': missing (a number is required)");
      }
      return std::nullopt;
    }
    const auto& v = j.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      throw InputError(file.string() + ": field '" + key + "': must be a finite number, got " +
                       v.dump());
    }
    return v.get<double>();
  };
  auto text = [&](const char* key) -> std::optional<std::string> {
    if (!j.contains(key)) return std::nullopt;
    if (!j.at(key).is_string()) {
      throw InputError(file.string() + ": field '" + key + "': must be a string, got " +
                       j.at(key).dump());
    }
    return j.at(key).get<std::string>();
  };

  RunSummary s;
  s.loaded_mass_kg = *number("loaded_mass_kg", true);
  s.work_J = *number("work_J", true);
  s.scenario = text("scenario");
  s.fidelity = text("fidelity");
  s.dig_start_s = number("dig_start_s", false);
  s.dig_end_s = number("dig_end_s", false);
  if (s.dig_start_s && s.dig_end_s && !(*s.dig_start_s < *s.dig_end_s)) {
    throw InputError(file.string() + ": field 'dig_end_s': must be later than dig_start_s");
  }
  // the rest, as it stands
  for (const auto& [key, value] : j.items()) {
    if (std::find(std::begin(kSummaryFields), std::end(kSummaryFields), key) == std::end(kSummaryFields))
      s.details[key] = value;
  }
  return s;
}

nlohmann::json to_json(const RunSummary& s) {
  nlohmann::json j;
  j["loaded_mass_kg"] = s.loaded_mass_kg;
  j["work_J"] = s.work_J;
  if (s.scenario) j["scenario"] = *s.scenario;
  if (s.fidelity) j["fidelity"] = *s.fidelity;
  if (s.dig_start_s) j["dig_start_s"] = *s.dig_start_s;
  if (s.dig_end_s) j["dig_end_s"] = *s.dig_end_s;
  if (!s.details.is_object()) throw Error("run summary: the details must be a JSON object");
  for (const auto& [key, value] : s.details.items()) {
    if (std::find(std::begin(kSummaryFields), std::end(kSummaryFields), key) != std::end(kSummaryFields))
      throw Error("run summary: detail '" + key + "' is one of the contract's fields; set the field instead");
    j[key] = value;
  }
  return j;
}

void save_summary(const fs::path& file, const RunSummary& s) {
  write_file_atomically(file, to_json(s).dump(2) + "\n");
}

Run load_run(const fs::path& dir) {
  if (!fs::is_directory(dir)) {
    throw InputError(dir.string() + ": not a run directory (expected " + kTimeseriesFile +
                     " and " + kSummaryFile + " inside)");
  }
  Run run;
  run.dir = dir;
  run.series = load_timeseries(dir / kTimeseriesFile);
  run.summary = load_summary(dir / kSummaryFile);
  return run;
}

TimeSeries select_window(const TimeSeries& series, double t0, double t1) {
  TimeSeries out;
  const auto& t = series[Channel::t];
  for (std::size_t n = 0; n < series.size(); ++n) {
    if (t[n] < t0 || t[n] > t1) continue;
    for (std::size_t c = 0; c < kChannelCount; ++c) out.columns[c].push_back(series.columns[c][n]);
  }
  return out;
}

std::vector<double> interpolate(const std::vector<double>& t, const std::vector<double>& f,
                                const std::vector<double>& t_new) {
  if (t.size() != f.size() || t.empty()) {
    throw Error("interpolate: t and f must have equal, non-zero length");
  }
  std::vector<double> out;
  out.reserve(t_new.size());
  std::size_t k = 0;  // t[k] <= tq < t[k+1], advanced monotonically when t_new is sorted
  for (double tq : t_new) {
    if (tq < t.front() || tq > t.back()) {
      throw InputError("interpolate: time " + format_number(tq) + " s lies outside the series [" +
                       format_number(t.front()) + ", " + format_number(t.back()) + "] s");
    }
    if (k + 1 < t.size() && tq < t[k]) k = 0;
    while (k + 1 < t.size() && t[k + 1] <= tq) ++k;
    if (k + 1 == t.size()) {
      out.push_back(f.back());
      continue;
    }
    const double w = (tq - t[k]) / (t[k + 1] - t[k]);
    out.push_back(f[k] + w * (f[k + 1] - f[k]));
  }
  return out;
}

TimeSeries resample(const TimeSeries& series, const std::vector<double>& t_new) {
  TimeSeries out;
  out[Channel::t] = t_new;
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    out.columns[c] = interpolate(series[Channel::t], series.columns[c], t_new);
  }
  return out;
}

}  // namespace talus::sim2real
