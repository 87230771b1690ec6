// The diagnosis as a person reads it (`talus diagnose` prints it, --out writes it as report.md):
// per run where the baseline's residual lies and what it moves with, the effects found, and the
// paper's error table before and after. The machine-readable twin is diagnosis_json.
#pragma once
#include <string>
#include <vector>

#include "sim2real/diagnose.hpp"
#include "sim2real/measured.hpp"

namespace talus::sim2real {

// residual cells listed per run in the report, largest excess first
inline constexpr std::size_t kSignatureCells = 6;
// a measured pile scan further than this from the simulated pile's gets a warning [m]: about one
// D400 particle diameter
inline constexpr double kScanWarning = 0.1;

// the largest residual cells of a run as a markdown table, with what each moves with
std::string residual_signature(const Residuals& residuals, const Run& measured, const Run& simulated);

// a line saying the residual was judged against the simulation's own spread too, with the spread's
// share of the variance per channel (Residuals::spread_share_of); empty without a spread
std::string spread_note(const Residuals& residuals);

// a line saying whether the verdict judged what is left against the simulation's sensitivity to
// the fitted parameters (the last of Diagnosis::sensitivity): the parameters within one standard
// error, the simulations it cost, and each judged run's excess without and with it, or why it was
// not used; empty when nothing was judged
std::string sensitivity_note(const Diagnosis& d);

// a line per chaos check (DiagnosisRound::chaos_checks): the addition, the reference's
// calibration excess without and with it, the share, held or refused; empty when none ran
std::string chaos_check_note(const Diagnosis& d);

// a line per joint refit (DiagnosisRound::refit): kept or not, the calibration log-ratio and the
// held-out excess before and after, its simulations, and each effect's spec before and after;
// empty when no round refitted
std::string refit_note(const Diagnosis& d);

// per-run error rows with their mean over the runs as the last row ("mean over runs"): the
// report's tables and the CSV files'
std::vector<TableRow> error_table(const std::vector<TableRow>& rows);

// the whole report in markdown; `runs` are the measured runs the diagnosis was made from, in order
std::string diagnosis_report(const Diagnosis& d, const std::vector<MeasuredRun>& runs);

}  // namespace talus::sim2real
