// The domain registry (domain.hpp): built-in domains by name, domain files by path.
#include "sim_driver/registry/domain.hpp"

#include "registry/builtin_domains.hpp"
#include "learner/input_error.hpp"

namespace hbirl {

double Simulation::render(int, int, int, cv::Mat&) const {
  throw InputError("domain", "this simulation has no camera");
}

const ObservedTrajectory& Simulation::observed(int) const {
  throw InputError("domain", "this simulation's frames are camera images, not observations");
}

Eigen::MatrixXd Domain::subject_prior(const std::vector<Trajectory>& truth,
                                      const std::vector<ObservedTrajectory>& observed, int symbols) const {
  if (observed.empty()) throw InputError("controlled run", "no controlled episodes: no subject prior");
  if (num_symbols() > 0 && symbols != num_symbols()) {
    throw InputError("observations.num_symbols",
                     std::to_string(symbols) + " differs from the domain's " + std::to_string(num_symbols()));
  }
  return controlled_run_prior(mdp(), truth, observed, symbols, controlled_prior_options());
}

void SensorRun::add_episodes(const std::vector<Trajectory>& controlled, const std::vector<Trajectory>& demonstrations,
                             std::vector<ObservedTrajectory> seen, const std::vector<char>& ended) {
  observed_ = std::move(seen);
  double start = 0.0;
  for (size_t i = 0; i < controlled.size() + demonstrations.size(); ++i) {
    const bool is_controlled = i < controlled.size();
    const Trajectory& steps = is_controlled ? controlled[i] : demonstrations[i - controlled.size()];
    observed_[i].ends_in_terminal = ended[i] != 0;
    episodes.push_back({is_controlled, start, steps, ended[i] != 0});
    start += static_cast<double>(steps.size()) * step_seconds;
  }
}

void subject_alone(std::vector<ObservedTrajectory>& observed, int sources) {
  for (auto& t : observed) {
    RowMatrix eta = RowMatrix::Zero(t.eta.rows(), sources);
    eta.col(0).setOnes();
    t.eta = std::move(eta);
  }
}

namespace {

constexpr int kMaxGridworldSize = 200;  // 40 000 states

// "gridworld:N" -> N; -1 when the spec is not of that form.
int gridworld_size_of(const std::string& spec) {
  const std::string prefix = "gridworld:";
  if (spec.rfind(prefix, 0) != 0) return -1;
  const std::string digits = spec.substr(prefix.size());
  if (digits.empty() || digits.size() > 4 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stoi(digits);
}

std::unique_ptr<Domain> gridworld_of_size(int size) {
  if (size < 2 || size > kMaxGridworldSize) {
    throw InputError("domain", "a Gridworld has 2 to " + std::to_string(kMaxGridworldSize) + " cells a side, not " +
                                   std::to_string(size));
  }
  return make_gridworld_domain(size);
}

}  // namespace

std::unique_ptr<Domain> builtin_domain(const std::string& name) {
  if (name == "onion") return make_onion_domain();
  if (name == "gridworld") return gridworld_of_size(5);
  const int size = gridworld_size_of(name);
  if (size >= 0) return gridworld_of_size(size);
  return nullptr;
}

std::unique_ptr<Domain> open_domain(const std::string& spec, const DomainOptions& options,
                                    std::vector<std::string>* warnings) {
  if (spec == "gridworld") return gridworld_of_size(options.gridworld_size);
  if (auto domain = builtin_domain(spec)) return domain;
  if (spec.empty()) throw InputError("domain", "is empty: give onion, gridworld or a domain file");
  return file_domain(spec, warnings);
}

}  // namespace hbirl
