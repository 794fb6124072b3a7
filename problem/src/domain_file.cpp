#include "problem/domain_file.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include "problem/json_node.hpp"
#include "readers.hpp"

namespace hbirl {

namespace {

constexpr double kSumTolerance = 1e-6;  // as for problem files: rounded probabilities are renormalised
constexpr int kMaxCount = 100000;
constexpr double kMaxObservations = 1e8;

// Rows of probabilities given as tuples (key..., symbol, p); listed rows must sum to 1,
// unlisted rows stay uniform. `key_of` maps a tuple to its row, validating the key.
template <typename KeyOf>
Eigen::MatrixXd read_probability_rows(const JsonNode& list, Eigen::Index rows, int symbols,
                                      const detail::TupleList& shape, KeyOf key_of) {
  const size_t tuple = shape.size;
  Eigen::MatrixXd o = Eigen::MatrixXd::Constant(rows, symbols, 1.0 / symbols);
  std::vector<double> sum(static_cast<size_t>(rows), -1.0);  // -1: not listed
  std::vector<size_t> first(static_cast<size_t>(rows), 0);
  std::set<std::pair<Eigen::Index, int>> seen;
  for (size_t i = 0; i < list.size(); ++i) {
    const JsonNode e = list[i];
    detail::expect_tuple(e, shape);
    const Eigen::Index r = key_of(e);
    const int w = static_cast<int>(e[tuple - 2].as_int(0, symbols - 1));
    const double p = e[tuple - 1].as_number(0.0, 1.0);
    if (!seen.emplace(r, w).second) e.fail("repeats an entry of the same row and symbol");
    auto& s = sum[static_cast<size_t>(r)];
    if (s < 0.0) {
      s = 0.0;
      first[static_cast<size_t>(r)] = i;
      o.row(r).setZero();
    }
    o(r, w) = p;
    s += p;
  }
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double s = sum[static_cast<size_t>(r)];
    if (s < 0.0) continue;
    if (std::abs(s - 1.0) > kSumTolerance) {
      list[first[static_cast<size_t>(r)]].fail("its row's probabilities sum to " + std::to_string(s) + ", expected 1");
    }
    o.row(r) /= s;
  }
  return o;
}

// What the parser builds of a domain file (json_document.hpp), and the keys its readers know.
const detail::JsonShape& sensor_shape() {
  using detail::JsonShape;
  static const JsonShape subject = JsonShape::list(detail::kSubjectObservationTuple),
                         confounder = JsonShape::list(detail::kConfounderObservationTuple),
                         end = JsonShape::list(detail::kEndObservationTuple);
  static const JsonShape shape = JsonShape::object({{"subject_observation", &subject},
                                                    {"confounder_observation", &confounder},
                                                    {"end_observation", &end},
                                                    {"end_reports", nullptr},
                                                    {"observations_per_step", nullptr},
                                                    {"eta", nullptr},
                                                    {"occlusion", nullptr},
                                                    {"trajectories", nullptr},
                                                    {"length", nullptr},
                                                    {"controlled_trajectories", nullptr},
                                                    {"step_seconds", nullptr}});
  return shape;
}

const detail::JsonShape& domain_shape() {
  using detail::JsonShape;
  // "demonstration": a problem file is a domain too; its data are not the domain's, and not built.
  static const JsonShape unread = JsonShape::unread();
  static const JsonShape shape = JsonShape::object({{"name", nullptr},
                                                    {"mdp", &detail::mdp_shape()},
                                                    {"observation_model", &detail::observation_model_shape()},
                                                    {"symbol_names", nullptr},
                                                    {"source_names", nullptr},
                                                    {"context_names", nullptr},
                                                    {"true_weights", nullptr},
                                                    {"sensor", &sensor_shape()},
                                                    {"demonstration", &unread}});
  return shape;
}

SensorSpec read_sensor(const JsonNode& node, const DomainSpec& domain, std::vector<std::string>* warnings) {
  node.check_keys(sensor_shape().keys(), warnings);
  if (!domain.observation_model) node.fail("needs observation_model (num_symbols and num_confounders) in the domain");
  if (!domain.true_weights) node.fail("needs true_weights in the domain (the simulated expert's reward)");
  const Mdp& mdp = domain.mdp;
  const int symbols = domain.num_symbols();
  const int elements = domain.num_sources() - 1;
  SensorSpec s;
  s.subject_o = Eigen::MatrixXd::Constant(mdp.num_pairs(), symbols, 1.0 / symbols);
  if (auto list = node.find("subject_observation")) {
    s.subject_o = read_probability_rows(*list, mdp.num_pairs(), symbols, detail::kSubjectObservationTuple,
                                        [&mdp](const JsonNode& e) {
                                          const int st = static_cast<int>(e[0].as_int(0, mdp.num_states - 1));
                                          const int a = static_cast<int>(e[1].as_int(0, mdp.num_actions - 1));
                                          return static_cast<Eigen::Index>(mdp.pair(st, a));
                                        });
  }
  s.confounder_o = Eigen::MatrixXd::Constant(elements, symbols, 1.0 / symbols);
  if (auto list = node.find("confounder_observation")) {
    if (elements == 0 && list->size() > 0) (*list)[0].fail("observation_model.num_confounders is 0");
    s.confounder_o = read_probability_rows(
        *list, elements, symbols, detail::kConfounderObservationTuple,
        [elements](const JsonNode& e) { return static_cast<Eigen::Index>(e[0].as_int(0, elements - 1)); });
  }
  // The end sensor (docs/MODEL.md "Sensors that see the end"): its true O_end per terminal
  // state (unlisted ones uniform) and how many reports each ending gets.
  const int end_symbols = domain.observation_model->num_end_symbols();
  for (const char* key : {"end_observation", "end_reports"}) {
    if (auto given = node.find(key); given && end_symbols == 0)
      given->fail("needs observation_model.end_sensor (the end sensor's alphabet)");
  }
  if (end_symbols > 0) {
    static const nlohmann::json kNoRows = nlohmann::json::array();
    s.end_o = read_probability_rows(node.find("end_observation").value_or(JsonNode(kNoRows, "")), mdp.num_states,
                                    end_symbols, detail::kEndObservationTuple, [&mdp](const JsonNode& e) {
                                      const int st = static_cast<int>(e[0].as_int(0, mdp.num_states - 1));
                                      if (!mdp.is_terminal(st))
                                        e[0].fail("state " + std::to_string(st) + " is not terminal");
                                      return static_cast<Eigen::Index>(st);
                                    });
    if (auto n = node.find("end_reports")) s.end_reports = static_cast<int>(n->as_int(1, 1000));
  }
  if (auto n = node.find("observations_per_step")) s.observations_per_step = static_cast<int>(n->as_int(1, kMaxCount));
  if (auto e = node.find("eta")) {
    s.eta = e->as_string();
    if (s.eta != "plausible" && s.eta != "uniform" && s.eta != "true") {
      e->fail("expected \"plausible\", \"uniform\" or \"true\", got \"" + s.eta + "\"");
    }
  }
  if (auto o = node.find("occlusion")) {
    s.occlusion = o->as_number(0.0, 1.0);
    if (s.occlusion >= 1.0) o->fail("must be below 1 (every step occluded: nothing to learn from)");
  }
  if (auto n = node.find("trajectories")) s.trajectories = static_cast<int>(n->as_int(1, kMaxCount));
  if (auto n = node.find("length")) s.length = static_cast<int>(n->as_int(1, kMaxCount));
  if (auto n = node.find("controlled_trajectories"))
    s.controlled_trajectories = static_cast<int>(n->as_int(1, kMaxCount));
  if (auto t = node.find("step_seconds")) {
    s.step_seconds = t->as_number(1e-6, 1e6);
  }
  // What a simulation holds in memory: every observation of the run.
  const double observations =
      static_cast<double>(s.trajectories + s.controlled_trajectories) * s.length * s.observations_per_step;
  if (observations > kMaxObservations) {
    node.fail("(trajectories + controlled_trajectories) * length * observations_per_step is " +
              std::to_string(observations) + ", more than " + std::to_string(kMaxObservations) +
              " observations to simulate");
  }
  return s;
}

DomainSpec parse_domain_document(const nlohmann::json& doc, const std::string& default_name,
                                 std::vector<std::string>* warnings) {
  const JsonNode root(doc, "");
  if (!doc.is_object()) root.fail("the domain file must be a JSON object");
  root.check_keys(domain_shape().keys(), warnings);
  DomainSpec d;
  Problem names;
  d.mdp = detail::read_mdp(root.at("mdp"), names, warnings);
  d.state_names = std::move(names.state_names);
  d.action_names = std::move(names.action_names);
  d.feature_names = std::move(names.feature_names);
  if (auto n = root.find("name")) {
    d.name = detail::read_domain_name(*n);
  } else {
    d.name = default_name;
    if (d.name.empty()) root.fail("has no \"name\"");
  }
  if (auto om = root.find("observation_model"))
    d.observation_model = detail::read_observation_model(*om, d.mdp, warnings);
  if (auto names_node = root.find("symbol_names")) {
    if (!d.observation_model) names_node->fail("needs observation_model (num_symbols)");
    d.symbol_names = detail::read_names(*names_node, d.num_symbols(), "symbol");
  }
  if (auto names_node = root.find("source_names")) {
    if (!d.observation_model) names_node->fail("needs observation_model (num_confounders)");
    d.source_names =
        detail::read_names(*names_node, d.num_sources(), "source: the subject, then each confounding element");
  }
  if (auto names_node = root.find("context_names")) d.context_names = detail::read_context_names(*names_node);
  if (auto tw = root.find("true_weights")) d.true_weights = detail::read_true_weights(*tw, d.mdp);
  if (auto sensor = root.find("sensor")) d.sensor = read_sensor(*sensor, d, warnings);
  return d;
}

}  // namespace

std::string domain_name_problem(const std::string& name) {
  if (name.empty() || name.size() > 64) return "must have 1 to 64 characters";
  for (const char c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return "may hold letters, digits, '_', '-' and '.' only";
  }
  return "";
}

std::string stem_name(const std::string& path) {
  std::string stem = std::filesystem::path(path).stem().string();
  for (char& c : stem) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  }
  return stem.substr(0, 64);
}

DomainSpec parse_domain(const std::string& text, const std::string& default_name, std::vector<std::string>* warnings) {
  return parse_domain_document(detail::parse_json_text(text, domain_shape()), default_name, warnings);
}

DomainSpec read_domain_file(const std::string& path, std::vector<std::string>* warnings) {
  // The text is let go once its document is built.
  const nlohmann::json doc = detail::parse_json_text(detail::read_text_file(path), domain_shape());
  return parse_domain_document(doc, stem_name(path), warnings);
}

}  // namespace hbirl
