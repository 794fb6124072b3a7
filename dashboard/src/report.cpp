#include "dashboard/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <fstream>
#include <sstream>

#include "dashboard/state.hpp"
#include "plot/gnuplot.hpp"
#include "learner/input_error.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"

namespace hbirl::dashboard {

namespace {

using nlohmann::json;

std::string html(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string number(const json& x, int digits = 4) {
  if (x.is_null()) return "–";
  std::ostringstream s;
  s.precision(digits);
  s << x.get<double>();
  return s.str();
}

std::vector<std::string> names_or_numbers(const json& names, size_t n, const std::string& prefix) {
  std::vector<std::string> out;
  for (size_t i = 0; i < n; ++i)
    out.push_back(i < names.size() ? names[i].get<std::string>() : prefix + std::to_string(i));
  return out;
}

// The upper end of a heat map's axis of n cells (cells centred on 0 .. n-1).
double edge(size_t n) { return static_cast<double>(n) - 0.5; }

// Plots the matrix $`name` (rows x cols) as a heat map: gnuplot's image, or, where the
// image cannot be drawn (it needs 2 x 2 cells at least: a single confounding element's
// row), a box per cell.
std::string heat_map(const std::string& name, size_t rows, size_t cols) {
  if (rows >= 2 && cols >= 2) return "plot $" + name + " matrix with image notitle\n";
  return "set style fill solid noborder\nplot $" + name +
         " matrix using 1:2:(0.5):(0.5):3 with boxxy fc palette notitle\n";
}

// Tics for a heat map's axis: label i at row or column i, or, with `block` > 1, at the
// middle of rows i * block .. (i + 1) * block - 1 (a state's rows, one per action).
std::string tics(const std::string& axis, const std::vector<std::string>& labels, size_t block = 1) {
  std::ostringstream s;
  s << "set " << axis << " (";
  for (size_t i = 0; i < labels.size(); ++i)
    s << (i ? ", " : "") << gnuplot_quoted(labels[i]) << " "
      << static_cast<double>(i * block) + 0.5 * static_cast<double>(block - 1);
  s << ")\n";
  return s.str();
}

// Lines between the blocks of `block` rows of a heat map `width` cells wide.
std::string block_separators(size_t rows, size_t block, size_t width) {
  std::ostringstream s;
  for (size_t r = block; r < rows; r += block)
    s << "set arrow from -0.5," << edge(r) << " to " << edge(width) << "," << edge(r)
      << " nohead front lc rgb '#9e9e9e' lw 0.5\n";
  return s.str();
}

void em_figure(const json& s, const std::string& stem, Report& r) {
  const json& em = s["em"];
  if (em.empty()) return;
  std::ostringstream data;
  bool ile = false;
  data << "$em << EOD\n";
  std::optional<double> strength;
  for (const auto& e : em) {
    // A new prior strength is a new objective: a blank line breaks gnuplot's line there.
    const double s_e = e.value("prior_strength", 0.0);
    if (strength && *strength != s_e) data << "\n";
    strength = s_e;
    data << e["iteration"].get<int>() << " "
         << (e["log_likelihood"].is_null() ? "NaN" : number(e["log_likelihood"], 12)) << " "
         << (e["ile"].is_null() ? "NaN" : number(e["ile"], 8)) << "\n";
    ile = ile || !e["ile"].is_null();
  }
  data << "EOD\nset title 'Learning: EM objective" << (ile ? " and ILE" : "") << " per EM iteration'\n"
       << "set xlabel 'EM iteration'\nset ylabel 'log Pr(observations | θ, O) + log prior'\nset grid\nset key bottom "
          "right box opaque\n";
  if (ile) data << "set y2label 'ILE (true reward)'\nset y2tics\nset ytics nomirror\nset y2range [0:*]\n";
  std::string plot = "plot $em using 1:2 with linespoints lw 2 pt 7 ps 0.6 lc rgb '#1565c0' title 'EM objective'";
  if (ile) plot += ", $em using 1:3 axes x1y2 with linespoints lw 2 pt 5 ps 0.6 lc rgb '#d84315' title 'ILE'";
  plot += "\n";
  const std::string why = run_gnuplot(stem, data.str(), plot, 800, 450);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

// The live estimates (--anytime): the confidence, and the relative ILE when known, against
// the demonstrations seen.
void estimates_figure(const json& s, const std::string& stem, Report& r) {
  const json& es = s["estimates"];
  if (es.empty()) return;
  std::ostringstream data;
  bool ile = false;
  data << "$estimates << EOD\n";
  for (const auto& e : es) {
    data << e["demonstrations"].get<int>() << " " << (e["confidence"].is_null() ? "NaN" : number(e["confidence"], 8))
         << " " << (e["ile_relative"].is_null() ? "NaN" : number(e["ile_relative"], 8)) << "\n";
    ile = ile || !e["ile_relative"].is_null();
  }
  data << "EOD\nset title 'While it watches: the estimate after each demonstration'\n"
       << "set xlabel 'demonstrations'\nset ylabel 'confidence (policy within 5% of optimal)'\nset yrange [0:1.05]\n"
       << "set grid\nset key center right box opaque\n";
  if (ile) data << "set y2label 'ILE / ||V*||_1 (true reward)'\nset y2tics\nset ytics nomirror\nset y2range [0:*]\n";
  std::string plot = "plot $estimates using 1:2 with linespoints lw 2 pt 7 lc rgb '#2e7d32' title 'confidence'";
  if (ile) plot += ", $estimates using 1:3 axes x1y2 with linespoints lw 2 pt 5 lc rgb '#d84315' title 'relative ILE'";
  plot += "\n";
  const std::string why = run_gnuplot(stem, data.str(), plot, 800, 450);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

void theta_figure(const json& s, const std::string& stem, Report& r) {
  const json& t = s["theta"];
  if (t.is_null()) return;
  const std::vector<double> learned = t["learned"];
  const std::vector<std::string> names = names_or_numbers(s["names"]["features"], learned.size(), "feature ");
  std::vector<double> truth;
  if (!t["true"].is_null()) truth = t["true"].get<std::vector<double>>();
  const auto scale = [](std::vector<double> w) {
    double m = 0.0;
    for (double x : w) m = std::max(m, std::abs(x));
    if (m > 0.0) {
      for (double& x : w) x /= m;
    }
    return w;
  };
  const std::vector<double> a = scale(learned), b = scale(truth);
  std::ostringstream data;
  data << "$theta << EOD\n";
  for (size_t k = 0; k < a.size(); ++k)
    data << '"' << names[k] << "\" " << a[k] << " " << (k < b.size() ? b[k] : 0.0) << "\n";
  data << "EOD\nset title 'Reward weights (each scaled to max |w| = 1)'\nset style data histograms\nset style "
          "histogram clustered gap 1\n"
       << "set style fill solid 0.85 border -1\nset yrange [-1.1:1.1]\nset grid ytics\nset key top right box opaque\n"
       << "set xtics rotate by -20\nset ylabel 'w / max |w|'\n";
  std::string plot = "plot $theta using 2:xtic(1) lc rgb '#1565c0' title " +
                     gnuplot_quoted(t["final"].get<bool>() ? "learned θ (final)" : "learned θ");
  if (!b.empty()) plot += ", '' using 3 lc rgb '#ef6c00' title 'true weights'";
  plot += "\n";
  const std::string why = run_gnuplot(stem, data.str(), plot, 800, 450);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

// Learned eta: the subject's share of eta as the labeller stated it and as learned, per
// context (those covering the most observations, as the live page shows them).
void eta_figure(const json& s, const std::string& stem, Report& r) {
  const json& e = s["eta"];
  if (e.is_null() || e["contexts"].empty()) return;
  const json& names = s["names"]["contexts"];
  std::ostringstream data;
  data << "$eta << EOD\n";
  for (const auto& c : e["contexts"]) {
    const auto k = c["context"].get<size_t>();
    std::string name = k < names.size() ? names[k].get<std::string>() : "context " + std::to_string(k);
    name.erase(std::remove(name.begin(), name.end(), '"'), name.end());  // a data column in double quotes
    data << '"' << name << " (" << number(c["observations"], 4) << ")\" " << number(c["stated"][0], 10) << " "
         << number(c["learned"][0], 10) << "\n";
  }
  data << "EOD\nset title "
       << gnuplot_quoted("Learned η per context, EM iteration " + std::to_string(e["iteration"].get<int>()))
       << "\nset style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.85 border -1\n"
       << "set yrange [0:1.2]\nset ytics 0, 0.2, 1\nset grid ytics\nset key top center horizontal box opaque\nset "
          "xtics rotate by -40 font ',8'\n"
       << "set ylabel 'η(subject)'\nset bmargin 9\nset rmargin 10\n";
  const std::string plot =
      "plot $eta using 2:xtic(1) lc rgb '#9e9e9e' title 'stated', '' using 3 lc rgb '#1565c0' title 'learned'\n";
  const std::string why = run_gnuplot(stem, data.str(), plot, 1000, 500);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

void posterior_figure(const json& s, const std::string& stem, Report& r) {
  const json& p = s["posterior"];
  if (p.is_null() || p["steps"].get<int>() == 0) return;
  const json& m = p["state_marginals"];
  const size_t steps = m.size(), states = m[0].size();
  const std::vector<std::string> names = names_or_numbers(s["names"]["states"], states, "state ");
  std::ostringstream data;
  data << "$post << EOD\n";
  for (size_t i = 0; i < states; ++i) {  // one row per state, one column per step
    for (size_t t = 0; t < steps; ++t) data << (t ? " " : "") << m[t][i].get<double>();
    data << "\n";
  }
  data << "EOD\n";
  const bool truth = !p["truth"].is_null();
  if (truth) {
    data << "$truth << EOD\n";
    for (size_t t = 0; t < steps; ++t) data << t << " " << p["truth"][t]["state"].get<int>() << "\n";
    data << "EOD\n";
  }
  data << "set title "
       << gnuplot_quoted("Posterior of the expert's state, episode " + std::to_string(p["episode"].get<int>()) +
                         ", EM iteration " + std::to_string(p["iteration"].get<int>()))
       << "\nset xlabel 'step'\nset cblabel 'Pr(state at step)'\nset cbrange [0:1]\n"
       << "set palette defined (0 'white', 1 '#1565c0')\nset xrange [-0.5:" << edge(steps)
       << "]\nset yrange [-0.5:" << edge(states) << "]\nset ytics font ',8'\n";
  std::vector<std::string> step_names;
  for (size_t t = 0; t < steps; ++t) step_names.push_back(std::to_string(t + 1));
  data << tics("xtics", step_names) << tics("ytics", names);
  std::string plot = "plot $post matrix with image notitle";
  if (truth) plot += ", $truth using 1:2 with points pt 2 ps 2 lw 2 lc rgb '#d84315' title 'ground truth'";
  plot += "\n";
  const std::string why = run_gnuplot(stem, data.str(), plot, 800, 640);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

void model_figure(const json& s, const std::string& stem, Report& r) {
  const json& m = s["model"];
  if (m.is_null()) return;
  const json& subject = m["subject"];
  const json& confounders = m["confounders"];
  const size_t pairs = subject.size(), symbols = subject[0].size();
  const int actions = m["num_actions"];
  const std::vector<std::string> symbol_names = names_or_numbers(s["names"]["symbols"], symbols, "symbol ");
  const size_t per_state = static_cast<size_t>(actions);
  const std::vector<std::string> state_names = names_or_numbers(s["names"]["states"], pairs / per_state, "state ");
  const std::vector<std::string> action_names = names_or_numbers(s["names"]["actions"], per_state, "action ");
  // A state's rows are its actions in order: the state named at their middle, the actions
  // in the axis label (one name per row would not fit beside a hundred rows).
  std::string action_order;
  for (size_t a = 0; a < per_state; ++a) action_order += (a ? ", " : "") + action_names[a];
  std::ostringstream data;
  data << "$subject << EOD\n";
  for (const auto& row : subject) {
    for (size_t w = 0; w < symbols; ++w) data << (w ? " " : "") << row[w].get<double>();
    data << "\n";
  }
  data << "EOD\n";
  if (!confounders.empty()) {
    data << "$elements << EOD\n";
    for (const auto& row : confounders) {
      for (size_t w = 0; w < symbols; ++w) data << (w ? " " : "") << row[w].get<double>();
      data << "\n";
    }
    data << "EOD\n";
  }
  data << "set palette defined (0 'white', 1 '#1565c0')\nset cbrange [0:1]\nset cblabel 'Pr(symbol)'\n";
  std::ostringstream plot;
  plot << "set multiplot layout 1," << (confounders.empty() ? 1 : 2) << "\n"
       << "set title "
       << gnuplot_quoted("Subject: O(symbol | state, action), EM iteration " +
                         std::to_string(m["iteration"].get<int>()))
       << "\n"
       << tics("xtics rotate by -60 font ',7'", symbol_names) << tics("ytics font ',7'", state_names, per_state)
       << "set ylabel " << gnuplot_quoted("state (rows: its actions " + action_order + ")") << " font ',8'\n"
       << block_separators(pairs, per_state, symbols) << "set xrange [-0.5:" << edge(symbols)
       << "]\nset yrange [-0.5:" << edge(pairs) << "]\n"
       << heat_map("subject", pairs, symbols) << "unset arrow\nunset ylabel\n";
  if (!confounders.empty()) {
    const std::vector<std::string> sources =
        names_or_numbers(s["names"]["sources"], confounders.size() + 1, "element ");
    plot << "set title 'Confounding elements: O(symbol | element)'\n"
         << tics("ytics font ',8'", std::vector<std::string>(sources.begin() + 1, sources.end()))
         << "set yrange [-0.5:" << edge(confounders.size()) << "]\n"
         << heat_map("elements", confounders.size(), symbols);
  }
  plot << "unset multiplot\n";
  const std::string why = run_gnuplot(stem, data.str(), plot.str(), 1200, 700);
  (why.empty() ? r.figures : r.problems).push_back(why.empty() ? stem : why);
}

// The recording, read through the run's key when it is signed; throws InputError("--log",
// ...) / ("--key", ...).
std::unique_ptr<services::Bus> open_recording(const std::string& log_path, const std::string& key_file,
                                              services::Counters& counters) {
  services::check_recording_key(log_path, key_file);
  return services::with_key(std::make_unique<services::LogBus>(log_path), key_file, counters,
                            services::KeyUse::kReader);
}

// A recording read in full must have given messages of one run: signed ones need the key,
// and a key shared by many runs needs the run's own key file.
void check_recording_read(const services::Counters& counters, const std::string& log_path,
                          const std::string& key_file) {
  if (counters.signed_unread > 0) {
    throw InputError("--key", "'" + log_path + "' holds " + std::to_string(counters.signed_unread) +
                                  " messages signed with a run key: give it (launch.sh wrote OUT/run.key)");
  }
  if (counters.messages_in == 0) {
    throw InputError("--log", "nothing in '" + log_path + "' could be read (" + std::to_string(counters.bad_messages) +
                                  " bad messages" +
                                  (counters.last_problem.empty() ? "" : "; the last: " + counters.last_problem) + ")");
  }
  if (counters.other_run > 0 && !services::RunKey::read(key_file).run()) {
    throw InputError("--log", "'" + log_path + "' holds messages of more than one run signed with this key (" +
                                  std::to_string(counters.other_run) +
                                  " not of the first; a replay recorded with it?): give the key file of the run to "
                                  "read (OUT/run.key names its run)");
  }
}

// The page's head and the run in a table: domain, episodes, frames, EM iterations, the
// final log-likelihood and ILE, the learned theta.
void page_summary(std::ostream& page, const json& s, const Report& report, const std::string& log_path) {
  page << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hbirl report</title>\n"
       << "<style>body{font-family:system-ui,sans-serif;max-width:1250px;margin:1em auto;padding:0 1em;color:#222}"
       << "img{max-width:100%;border:1px solid #ddd}table{border-collapse:collapse}td,th{padding:.2em .7em;"
       << "border-bottom:1px solid #eee;text-align:left}figure{margin:1.2em "
          "0}figcaption{color:#555}</style></head><body>\n"
       << "<h1>hbirl report</h1>\n<p>From <code>" << html(log_path) << "</code>: " << report.messages << " messages ("
       << report.bad_messages
       << " that did not decode or validate). The data of every figure: <a href=\"state.json\">state.json</a>.</p>\n";
  const json& run = s["run"];
  page << "<table><tr><th>domain</th><td>" << html(s["domain"].get<std::string>()) << "</td></tr>"
       << "<tr><th>episodes</th><td>" << run["episodes_ended"] << "</td></tr><tr><th>camera frames</th><td>"
       << run["frames"] << "</td></tr><tr><th>EM iterations</th><td>" << s["em"].size() << "</td></tr>";
  if (!s["reward"].is_null()) {
    page << "<tr><th>final log-likelihood</th><td>" << number(s["reward"]["log_likelihood"], 10) << "</td></tr>"
         << "<tr><th>ILE</th><td>" << number(s["reward"]["ile"]) << "</td></tr>";
  }
  if (!s["theta"].is_null()) {
    page << "<tr><th>learned θ</th><td>";
    const auto names = names_or_numbers(s["names"]["features"], s["theta"]["learned"].size(), "feature ");
    for (size_t k = 0; k < names.size(); ++k)
      page << (k ? ", " : "") << html(names[k]) << " " << number(s["theta"]["learned"][k]);
    page << "</td></tr>";
  }
  page << "</table>\n";
}

// The learned reward's policy by state and action names: what a robot would do.
void page_policy(std::ostream& page, const json& s) {
  if (s["reward"].is_null() || !s["reward"].contains("policy")) return;
  const json& policy = s["reward"]["policy"];
  page << "<h2>Learned policy</h2>\n<p>In each state that is not terminal, the action the learned reward's optimal "
          "policy takes (what a robot would do) and the probability that the expert takes it by the learned soft "
          "policy (MaxCausalEnt's model of the expert).</p>\n<table><tr><th>state</th><th>action</th>"
          "<th>probability</th></tr>\n";
  for (const auto& step : policy["shown"]) {
    const auto name = [](const json& x) { return x.is_string() ? x.get<std::string>() : x.dump(); };
    page << "<tr><td>" << html(name(step["state"])) << "</td><td>" << html(name(step["action"])) << "</td><td>"
         << number(step["probability"]) << "</td></tr>\n";
  }
  page << "</table>\n";
  const size_t shown = policy["shown"].size(), states = policy["states"].get<size_t>();
  if (states > shown)
    page << "<p>... and " << states - shown << " more states: the whole policy is in the run's result.json "
         << "(\"policy\").</p>\n";
}

// The last camera frame, with the legend of the sources' colours.
void page_camera(std::ostream& page, const json& s) {
  const json& c = s["camera"];
  page << "<figure><img src=\"camera.png\" alt=\"the last camera frame\"><figcaption>The last camera frame (episode "
       << c["episode"] << ", step " << c["step"] << ", frame " << c["frame"]
       << "), each detection boxed in the colour of its most likely source by the labeller's η:";
  const json& sources = s["names"]["sources"];
  for (size_t z = 0; z < sources.size(); ++z) {
    page << " <span style=\"color:" << s["source_colours"][z % s["source_colours"].size()].get<std::string>()
         << "\">■</span> " << html(sources[z].get<std::string>());
  }
  page << ".</figcaption></figure>\n";
}

// Each figure drawn, with its caption and its files.
void page_figures(std::ostream& page, const Report& report, const std::filesystem::path& dir) {
  const std::vector<std::pair<std::string, std::string>> captions = {
      {"em", "Log-likelihood of the observations (and the ILE under the true reward, when known) per EM iteration."},
      {"estimates",
       "While it watched (--anytime): after each demonstration, the confidence that the policy learned so far is "
       "within 5% of the optimal value and, with the expert's weights known, its relative ILE."},
      {"theta", "Learned reward weights against the expert's true weights."},
      {"posterior",
       "The expert's posterior state at each step of the newest demonstration (sources summed out), "
       "with the ground truth."},
      {"observation_model",
       "The learned observation model: the subject's per (state, action), and each confounding element's."},
      {"eta",
       "Learned η: per context (the labeller's rule, else each distinct stated η), the subject's share as stated and "
       "as "
       "learned from the data, for the contexts that cover the most observations (their number in brackets)."}};
  for (const auto& [stem, caption] : captions) {
    const std::string path = (dir / stem).string();
    if (std::find(report.figures.begin(), report.figures.end(), path) == report.figures.end()) continue;
    page << "<figure><a href=\"" << stem << ".png\"><img src=\"" << stem << ".svg\" alt=\"" << html(caption)
         << "\"></a><figcaption>" << html(caption) << " (<a href=\"" << stem << ".png\">PNG</a>, <a href=\"" << stem
         << ".svg\">SVG</a>, <a href=\"" << stem << ".gp\">gnuplot script</a>)</figcaption></figure>\n";
  }
}

// The services' last status, and the figures that could not be drawn.
void page_services(std::ostream& page, const json& s, const Report& report) {
  page << "<h2>Services</h2>\n<table><tr><th>service</th><th>id</th><th>last state</th><th>messages in</th><th>out</th>"
       << "<th>bad messages</th><th>gaps</th><th>note</th></tr>\n";
  for (const auto& x : s["services"]) {
    page << "<tr><td>" << html(x["service"].get<std::string>()) << "</td><td>" << html(x["id"].get<std::string>())
         << "</td><td>" << html(x["state"].get<std::string>()) << "</td><td>" << x["messages_in"] << "</td><td>"
         << x["messages_out"] << "</td><td>" << x["bad_messages"] << "</td><td>" << x["gaps"] << "</td><td>"
         << html(x["detail"].get<std::string>()) << "</td></tr>\n";
  }
  page << "</table>\n";
  for (const auto& p : report.problems) page << "<p>Not drawn: " << html(p) << "</p>\n";
}

}  // namespace

Report write_report(const std::string& log_path, const std::string& out_dir, std::shared_ptr<const Domain> domain,
                    const std::string& key_file) {
  services::Counters counters;
  counters.service = "hbirl report";
  counters.quiet = true;
  const std::unique_ptr<services::Bus> signed_or_not = open_recording(log_path, key_file, counters);
  services::Bus& bus = *signed_or_not;
  DashboardState state(std::move(domain));
  state.subscribe(bus, counters);
  while (bus.handle(0) >= 0) {
  }
  check_recording_read(counters, log_path, key_file);
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  if (error) throw InputError("--out", "cannot create '" + out_dir + "': " + error.message());
  const std::filesystem::path dir(out_dir);
  Report report;
  report.messages = counters.messages_in;
  report.bad_messages = counters.bad_messages;
  const json s = state.json(services::wall_utime());
  report.finished = !s["reward"].is_null();
  {
    std::ofstream out(dir / "state.json");
    out << s.dump(1, ' ', false, json::error_handler_t::replace) << "\n";
    if (!out) throw InputError("--out", "cannot write " + (dir / "state.json").string());
  }
  const std::vector<unsigned char> frame = state.frame_png();
  if (!frame.empty()) {
    std::ofstream out(dir / "camera.png", std::ios::binary);
    out.write(reinterpret_cast<const char*>(frame.data()), static_cast<std::streamsize>(frame.size()));
  }
  em_figure(s, (dir / "em").string(), report);
  estimates_figure(s, (dir / "estimates").string(), report);
  theta_figure(s, (dir / "theta").string(), report);
  posterior_figure(s, (dir / "posterior").string(), report);
  model_figure(s, (dir / "observation_model").string(), report);
  eta_figure(s, (dir / "eta").string(), report);

  std::ostringstream page;
  page_summary(page, s, report, log_path);
  if (!frame.empty()) page_camera(page, s);
  page_figures(page, report, dir);
  page_policy(page, s);
  page_services(page, s, report);
  page << "</body></html>\n";
  report.page = (dir / "index.html").string();
  std::ofstream out(report.page);
  out << page.str();
  if (!out) throw InputError("--out", "cannot write " + report.page);
  return report;
}

}  // namespace hbirl::dashboard
