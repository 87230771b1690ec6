#include "sim2real/report.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "sim2real/residuals.hpp"
#include "sim2real/table.hpp"

namespace talus::sim2real {

std::string residual_signature(const Residuals& res, const Run& measured, const Run& simulated) {
  std::vector<ResidualCell> cells = res.cells;
  std::sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.excess > b.excess; });
  std::ostringstream s;
  s << "| channel | phase | RMS residual | mean residual | noise σ | excess | moves most with (r) |\n"
    << "|---|---|---|---|---|---|---|\n";
  std::size_t shown = 0;
  for (const auto& c : cells) {
    if (shown == kSignatureCells || c.excess <= 0.0) break;
    const auto r = residual_series(simulated, measured, c.channel);
    const Correlate k = strongest_correlate(r, measured);
    s << "| " << kChannelNames[c.channel] << " | " << res.phases[c.phase].name << " | " << std::setprecision(3) << c.rms
      << " | " << c.mean << " | " << c.sigma << " | " << std::setprecision(2) << std::fixed << c.excess
      << std::defaultfloat << " | " << k.quantity << " (" << std::setprecision(2) << k.r << ") |\n";
    ++shown;
  }
  if (shown == 0) s << "| (every channel within noise) | | | | | | |\n";
  return s.str();
}

std::string spread_note(const Residuals& res) {
  if (res.spread_members == 0) return "";
  std::ostringstream s;
  s << "Judged against the sensor noise and the simulation's own spread over " << res.spread_members
    << " piles, σ² + (1 + 1/N) v (MSE_w: the mean of r² / (1 + (1 + 1/N) v / σ²)); the spread's "
       "mean share of that variance:";
  for (std::size_t c = 1; c < kChannelCount; ++c)
    s << (c > 1 ? ", " : " ") << kChannelNames[c] << " " << std::setprecision(2) << std::fixed
      << res.spread_share_of(c) << std::defaultfloat;
  s << ".";
  // an estimated variance is judged by Student's t with its degrees of freedom
  if (!res.variance_dof.empty()) {
    s << " The piles' variance is an estimate, so each sample's r / √w is judged by Student's t "
         "with its degrees of freedom and counted on the normal scale in MSE_w (Satterthwaite's "
         "degrees, from these):";
    for (std::size_t c = 1; c < kChannelCount; ++c)
      s << (c > 1 ? ", " : " ") << kChannelNames[c] << " " << std::setprecision(1) << std::fixed
        << res.variance_dof[c] << std::defaultfloat;
    s << ".";
  }
  s << "\n\n";
  return s.str();
}

std::string sensitivity_note(const Diagnosis& d) {
  if (d.sensitivity.empty()) return "";
  const SensitivityJudgement& j = d.sensitivity.back();
  std::ostringstream s;
  s << std::setprecision(4);
  if (!j.used) {
    s << "\nSensitivity spread not used (" << j.after << "): " << j.reason << ".\n";
    return s.str();
  }
  s << "\nSensitivity spread (" << j.after
    << "): what is left judged against σ² + (1 + 1/N) v + s, s from the fitted parameters within "
       "one standard error (";
  for (std::size_t k = 0; k < j.parameters.size(); ++k) {
    const auto& p = j.parameters[k];
    s << (k ? ", " : "") << p.effect << " " << p.parameter << " " << p.value << " [" << p.low
      << ", " << p.high << "] " << p.unit;
  }
  s << "; " << j.design_points << " simulations per run judged, " << j.curvature_simulations
    << " for the curvature, whose likelihood counted the calibration runs' samples as "
    << std::setprecision(2) << j.effective_sample_share
    << " of their number for the residual's correlation in time); excess";
  for (std::size_t i = 0; i < j.runs.size(); ++i)
    if (j.runs[i].used)
      s << " run " << i << " " << std::setprecision(3) << j.runs[i].excess_without << " -> "
        << j.runs[i].excess_with;
  s << ".\n";
  return s.str();
}

std::string chaos_check_note(const Diagnosis& d) {
  std::ostringstream s;
  auto line = [&](const std::string& where, const ChaosCheck& c) {
    s << "\nChaos check " << where << " (its share was counted on the calibration runs, so they "
      << "were dug again on a second ensemble of piles): ";
    for (std::size_t e = 0; e < c.effects.size(); ++e) s << (e ? " and " : "") << c.effects[e];
    s << ", calibration excess " << std::setprecision(3) << c.excess_before << " -> "
      << c.excess_with << " there (explains " << std::setprecision(2) << 100.0 * c.explained
      << " %): " << (c.passed ? "holds" : "refused, a chance fit of the model's own piles")
      << ".\n";
  };
  for (std::size_t k = 0; k < d.rounds.size(); ++k)
    for (const ChaosCheck& c : d.rounds[k].chaos_checks)
      line("in round " + std::to_string(k + 1), c);
  for (const ChaosCheck& c : d.discovery_chaos_checks) line("of the discovery", c);
  return s.str();
}

std::string refit_note(const Diagnosis& d) {
  std::ostringstream s;
  for (std::size_t k = 0; k < d.rounds.size(); ++k) {
    const auto& r = d.rounds[k].refit;
    if (!r) continue;
    s << "\nRefitted together after round " << k + 1 << " (" << (r->kept ? "kept" : "not kept")
      << "; calibration log-ratio " << std::setprecision(3) << r->log_ratio_before << " -> "
      << r->log_ratio_after << ", held-out excess " << r->excess_validation_before << " -> "
      << r->excess_validation_after << ", " << r->simulations << " simulations):";
    for (std::size_t e = 0; e < r->before.size(); ++e)
      s << (e ? "; " : " ") << r->before[e] << " -> " << r->after[e];
    s << ".\n";
  }
  return s.str();
}

std::vector<TableRow> error_table(const std::vector<TableRow>& rows) {
  std::vector<TableRow> table = rows;
  table.push_back(mean_row(rows, "mean over runs"));
  return table;
}

std::string diagnosis_report(const Diagnosis& d, const std::vector<MeasuredRun>& runs) {
  // per run: where the residual lay
  std::ostringstream report;
  report << "# talus diagnose\n\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const bool cal = std::find(d.calibration.begin(), d.calibration.end(), i) != d.calibration.end();
    const bool val = std::find(d.validation.begin(), d.validation.end(), i) != d.validation.end();
    report << "## " << runs[i].run.label() << " (" << d.runs[i] << "; "
           << (cal && val ? "calibration and validation"
               : cal      ? "calibration"
                          : "validation")
           << ")\n\n"
           << "Baseline residual, largest cells (excess = ln max("
           << (d.residuals_before[i].spread_members > 0 ? "MSE_w / (κ σ²), 1), κ " : "MSE / (")
           << kNoiseAllowance
           << (d.residuals_before[i].spread_members > 0
                   ? " or more where the spread's samples are correlated"
                   : " σ²), 1)")
           << "; run total " << std::setprecision(3) << d.residuals_before[i].excess << "):\n\n"
           << residual_signature(d.residuals_before[i], runs[i].run, d.simulated_before[i]) << "\n"
           << spread_note(d.residuals_before[i]);
    if (d.scan_rms_m[i] && *d.scan_rms_m[i] > kScanWarning)
      report << "Warning: the measured pile scan lies " << *d.scan_rms_m[i] << " m (RMS) from the simulated pile's; "
             << "the residual includes that difference.\n\n";
  }
  // what was found
  report << "## Effects\n\n";
  if (d.found.empty()) {
    report << (d.unexplained ? "None added: no candidate explains " + std::to_string(int(100 * kMinExplained)) +
                                   " % of the residual. UNEXPLAINED.\n"
                             : "None added: the baseline residual is within the noise of the data.\n");
  } else {
    for (const auto& f : d.found) {
      // one of a set: the share is the set's, which the line says
      const std::string with = listed(f.fitted_with, ", ", " and ");
      report << "- " << f.spec
             << (with.empty() ? " (explains "
                              : " (fitted with " + with + ", which together explain ")
             << std::setprecision(3) << 100.0 * f.explained << " % of the excess of the "
             << f.explained_on << " runs)";
      // a value read off the likelihood's trend rather than found by the optimiser
      if (f.trend_estimate)
        report << "; its value is the minimum of the likelihood's trend over the fit's window, "
               << "whose samples had " << f.local_minima << " local minima (a rough likelihood: a "
               << "chaotic dig)";
      report << "\n";
    }
    report << (d.unexplained ? "\nAn excess beyond noise remains: UNEXPLAINED in part.\n" : "\nWhat remains is within noise.\n");
  }
  report << chaos_check_note(d);
  report << refit_note(d);
  report << sensitivity_note(d);
  // what the discovery fitted beyond the candidates
  if (d.discovery_ran) {
    report << "\n## Discovery (a term outside the candidates)\n\n";
    if (d.discovered) {
      report << "Added: " << d.discovered->expression << "\n(`--effect " << d.discovered->spec
             << "`; explains " << std::setprecision(3) << 100.0 * d.discovered->explained
             << " % of the excess of the " << d.discovered->explained_on
             << " runs; channels it moves: ";
      for (std::size_t k = 0; k < d.discovered->channels.size(); ++k)
        report << (k ? ", " : "") << d.discovered->channels[k];
      report << ")\n";
    } else {
      report << "Nothing added: no sparse correction explains " << int(100 * kMinExplained)
             << " % of the excess left.\n";
    }
    report << "\n| target | correction | held-out MSE cut | explains |\n|---|---|---|---|\n";
    for (const auto& c : d.discovery_tried) {
      report << "| " << c.target.label() << " | " << (c.terms.empty() ? "(none)" : c.expression)
             << " | "
             << (c.terms.empty() || !(c.cv_mse_none > 0.0)
                     ? std::string("-")
                     : std::to_string(int(std::lround(100.0 * (1.0 - c.cv_mse / c.cv_mse_none)))) +
                           " %")
             << " | "
             << (c.simulated ? std::to_string(int(std::lround(100.0 * c.explained))) + " % (" +
                                   c.explained_on + ")"
                             : "-")
             << " |\n";
    }
  }
  report << "\nExcess per run: before " << std::setprecision(3) << d.excess_before << ", after " << d.excess_after
         << " (noise alone leaves less than " << kSignificantExcess << "); " << d.simulations << " simulations in "
         << std::setprecision(3) << d.wall_s << " s.\n\n## Error before\n\n";
  // the errors before and after, with their mean over the runs
  report << table_markdown(error_table(d.error_before), 3) << "\n## Error after\n\n"
         << table_markdown(error_table(d.error_after), 3);
  return report.str();
}

}  // namespace talus::sim2real
