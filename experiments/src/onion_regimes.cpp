#include "experiments/onion_regimes.hpp"

#include <map>
#include <sstream>

#include "experiments/summary.hpp"

namespace hbirl::onion {

namespace {

std::string scene_name(bool mirror, double eta_power) {
  std::ostringstream out;
  out << (mirror ? "with the mirror" : "no mirror") << ", eta ";
  if (eta_power == 1.0) {
    out << "as stated";
  } else {
    out << (eta_power > 1.0 ? "overconfident" : "timid") << " (power " << eta_power << ")";
  }
  return out.str();
}

// (mirror, eta power) -> method label -> share -> ILE values.
using Cells = std::map<std::pair<bool, double>, std::map<std::string, std::map<double, std::vector<double>>>>;

Cells cells_of(const std::vector<OnionRegimeRun>& runs) {
  Cells cells;
  for (const auto& r : runs) {
    if (!r.run.error.empty()) continue;
    cells[{r.regime.mirror, r.regime.eta_power}][method_label(r.run.method)][r.regime.foreground_share].push_back(
        r.run.ile);
  }
  return cells;
}

}  // namespace

std::vector<OnionRegime> onion_regimes(const OnionRegimesOptions& o) {
  std::vector<OnionRegime> out;
  for (double power : o.eta_powers) {
    for (bool mirror : o.mirrors) {
      for (double share : o.shares) out.push_back({share, mirror, power});
    }
  }
  return out;
}

std::vector<OnionRegimeRun> run_onion_regimes(const OnionRegimesOptions& o) {
  const std::vector<OnionRegime> regimes = onion_regimes(o);
  std::vector<OnionRegimeRun> out;
  const int per_regime = o.base.runs * static_cast<int>(o.base.trajectories.size() * o.base.methods.size());
  const int total = per_regime * static_cast<int>(regimes.size());
  for (size_t i = 0; i < regimes.size(); ++i) {
    OnionExperimentOptions options = o.base;
    options.scene.mirror = regimes[i].mirror;
    options.scene.foreground_person = regimes[i].foreground_share > 0.0;
    options.scene.foreground_share = regimes[i].foreground_share;
    options.eta_power = regimes[i].eta_power;
    const int before = per_regime * static_cast<int>(i);
    if (o.progress) options.progress = [&o, before, total](int done, int) { o.progress(before + done, total); };
    for (OnionRun& r : run_onion_experiment(options)) out.push_back({regimes[i], std::move(r)});
  }
  return out;
}

std::string onion_regimes_csv(const std::vector<OnionRegimeRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "foreground_share,mirror,eta_power,run,method,trajectories,ile,ile_relative,policy_agreement,em_evaluations,"
         "seconds,error\n";
  for (const auto& [regime, r] : runs) {
    out << regime.foreground_share << "," << (regime.mirror ? 1 : 0) << "," << regime.eta_power << "," << r.run << ","
        << method_key(r.method) << "," << r.trajectories << "," << r.ile << "," << r.ile_relative << ","
        << r.policy_agreement << "," << r.em_evaluations << "," << r.seconds << "," << csv_text(r.error) << "\n";
  }
  return out.str();
}

std::string onion_regimes_summary(const std::vector<OnionRegimeRun>& runs, const std::string& footer) {
  const Cells cells = cells_of(runs);
  std::ostringstream md;
  md.precision(3);
  md << "# Onion sorting: where each method breaks\n\nMean ILE ± 95% CI as the foreground person's share of the time "
        "in front "
        "of the expert grows (0: no foreground person).\n";
  for (const auto& [scene, methods] : cells) {
    md << "\n## " << scene_name(scene.first, scene.second) << "\n\n| method |";
    const auto& shares = methods.begin()->second;
    for (const auto& [share, values] : shares) md << " " << share << " |";
    md << "\n|---|";
    for (size_t i = 0; i < shares.size(); ++i) md << "---|";
    md << "\n";
    for (const auto& [method, by_share] : methods) {
      md << "| " << method << " |";
      for (const auto& [share, values] : by_share) {
        const SummaryRow r = mean_and_ci(values);
        md << " " << r.mean << " ± " << r.ci95 << " |";
      }
      md << "\n";
    }
  }
  md << "\n" << footer << "\n";
  return md.str();
}

std::string draw_onion_regimes_figure(const std::vector<OnionRegimeRun>& runs, const std::string& path_stem) {
  const Cells cells = cells_of(runs);
  std::ostringstream data, plot;
  int panel = 0;
  plot << "set multiplot layout 2," << (cells.size() + 1) / 2
       << " title 'Onion sorting: ILE vs the foreground person''s share (95% CI)'\n";
  for (const auto& [scene, methods] : cells) {
    int m = 0;
    std::ostringstream lines;
    for (const auto& [method, by_share] : methods) {
      data << "$p" << panel << "m" << m << " << EOD\n";
      for (const auto& [share, values] : by_share) {
        const SummaryRow r = mean_and_ci(values);
        data << share << " " << r.mean << " " << r.ci95 << "\n";
      }
      data << "EOD\n";
      lines << (m ? ", " : "") << "$p" << panel << "m" << m << " using 1:2:3 with yerrorlines ls " << m + 1 << " title "
            << gnuplot_quoted(method);
      ++m;
    }
    plot << "set title " << gnuplot_quoted(scene_name(scene.first, scene.second)) << "\nplot " << lines.str() << "\n";
    ++panel;
  }
  plot << "unset multiplot\n";
  data << "set grid\nset key top left box opaque font ',9'\nset yrange [0:*]\nset xrange [-0.05:0.95]\n"
       << "set xlabel 'foreground person in front of the expert (share of the time)'\nset ylabel 'ILE'\n"
       << "set style line 1 lc rgb '#1b9e77' lw 2 pt 7\nset style line 2 lc rgb '#d95f02' lw 2 pt 5\n"
       << "set style line 3 lc rgb '#7570b3' lw 2 pt 9\nset style line 4 lc rgb '#e7298a' lw 2 pt 11\n"
       << "set style line 5 lc rgb '#66a61e' lw 2 pt 13\n";
  return run_gnuplot(path_stem, data.str(), plot.str(), 1200, 850);
}

}  // namespace hbirl::onion
