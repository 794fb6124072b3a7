#include "experiments/summary.hpp"

#include <boost/math/distributions/students_t.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace hbirl {

std::vector<std::string> csv_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

std::string csv_text(std::string text) {
  std::replace(text.begin(), text.end(), ',', ';');
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

std::pair<double, double> wilson(int k, int n) {
  if (n == 0) return {0.0, 1.0};
  const double z = 1.959963984540054;
  const double p = static_cast<double>(k) / n;
  const double d = 1.0 + z * z / n;
  const double centre = (p + z * z / (2.0 * n)) / d;
  const double half = z * std::sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / d;
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

SummaryRow mean_and_ci(const std::vector<double>& values) {
  SummaryRow row;
  row.n = static_cast<int>(values.size());
  if (row.n == 0) return row;
  double sum = 0.0;
  for (double x : values) sum += x;
  row.mean = sum / row.n;
  double ss = 0.0;
  for (double x : values) ss += (x - row.mean) * (x - row.mean);
  row.sd = row.n > 1 ? std::sqrt(ss / (row.n - 1)) : 0.0;
  if (row.n > 1) {
    const boost::math::students_t t(row.n - 1);
    row.ci95 = boost::math::quantile(t, 0.975) * row.sd / std::sqrt(static_cast<double>(row.n));
  }
  return row;
}

std::vector<SummaryRow> summarise(const std::vector<std::string>& methods, const std::vector<int>& xs,
                                  const std::vector<double>& values) {
  std::vector<std::string> order;
  std::map<std::pair<std::string, int>, std::vector<double>> groups;
  for (size_t i = 0; i < values.size(); ++i) {
    if (std::find(order.begin(), order.end(), methods[i]) == order.end()) order.push_back(methods[i]);
    groups[{methods[i], xs[i]}].push_back(values[i]);
  }
  std::vector<SummaryRow> rows;
  for (const auto& method : order) {
    for (const auto& [key, v] : groups) {
      if (key.first != method) continue;
      SummaryRow row = mean_and_ci(v);
      row.method = method;
      row.x = key.second;
      rows.push_back(row);
    }
  }
  return rows;
}

std::string summary_csv(const std::vector<SummaryRow>& rows, const std::string& x_name) {
  std::ostringstream out;
  out.precision(10);
  out << "method," << x_name << ",runs,mean,sd,ci95\n";
  for (const auto& r : rows)
    out << r.method << "," << r.x << "," << r.n << "," << r.mean << "," << r.sd << "," << r.ci95 << "\n";
  return out.str();
}

std::string summary_markdown(const std::vector<SummaryRow>& rows, const std::string& x_name,
                             const std::string& value_name) {
  std::vector<std::string> methods;
  std::vector<int> xs;
  for (const auto& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
    if (std::find(xs.begin(), xs.end(), r.x) == xs.end()) xs.push_back(r.x);
  }
  std::sort(xs.begin(), xs.end());
  std::ostringstream out;
  out << "| " << x_name << " |";
  for (const auto& m : methods) out << " " << m << " |";
  out << "\n|---|";
  for (size_t i = 0; i < methods.size(); ++i) out << "---|";
  out << "\n";
  char cell[64];
  for (int x : xs) {
    out << "| " << x << " |";
    for (const auto& m : methods) {
      const auto it =
          std::find_if(rows.begin(), rows.end(), [&](const SummaryRow& r) { return r.method == m && r.x == x; });
      if (it == rows.end()) {
        out << " |";
      } else {
        std::snprintf(cell, sizeof cell, " %.3f ± %.3f |", it->mean, it->ci95);
        out << cell;
      }
    }
    out << "\n";
  }
  out << "\n"
      << value_name << ": mean ± 95% confidence half-width over " << (rows.empty() ? 0 : rows.front().n)
      << " runs per cell.\n";
  return out.str();
}

std::string draw_figure(const std::vector<SummaryRow>& rows, const FigureSpec& spec) {
  std::vector<std::string> methods;
  for (const auto& r : rows) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
  }
  std::ostringstream data;
  for (size_t m = 0; m < methods.size(); ++m) {
    data << "$m" << m << " << EOD\n";
    for (const auto& r : rows) {
      if (r.method == methods[m]) data << r.x << " " << r.mean << " " << r.ci95 << "\n";
    }
    data << "EOD\n";
  }
  int x_min = rows.empty() ? 0 : rows.front().x;
  int x_max = x_min;
  for (const auto& r : rows) {
    x_min = std::min(x_min, r.x);
    x_max = std::max(x_max, r.x);
  }
  std::ostringstream plot;
  plot << "plot ";
  for (size_t m = 0; m < methods.size(); ++m) {
    if (m > 0) plot << ", \\\n     ";
    plot << "$m" << m << " using 1:2:3 with yerrorlines linestyle " << (m + 1) << " title '" << methods[m] << "'";
  }
  plot << "\n";
  std::ostringstream settings;
  settings << data.str() << "set title '" << spec.title << "'\n"
           << "set xlabel '" << spec.x_label << "'\nset ylabel '" << spec.y_label << "'\n"
           << "set key right center box opaque\nset grid\nset yrange [0:*]\n"
           << "set xrange [" << x_min - 0.5 << ":" << x_max + 0.5 << "]\n"
           << "set style line 1 lc rgb '#1b9e77' lw 2 pt 7 ps 1.0\n"
           << "set style line 2 lc rgb '#d95f02' lw 2 pt 5 ps 1.0\n"
           << "set style line 3 lc rgb '#7570b3' lw 2 pt 9 ps 1.1\n"
           << "set style line 4 lc rgb '#e7298a' lw 2 pt 11 ps 1.1\n"
           << "set style line 5 lc rgb '#66a61e' lw 2 pt 13 ps 1.1\n"
           << "set style line 6 lc rgb '#e6ab02' lw 2 pt 3 ps 1.0\n";
  return run_gnuplot(spec.path_stem, settings.str(), plot.str(), 900, 600);
}

}  // namespace hbirl
