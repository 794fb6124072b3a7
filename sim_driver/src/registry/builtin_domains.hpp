#pragma once
// The built-in domains the registry (registry.cpp) makes, each in its own folder, and
// what the sensor-simulated ones share.
#include <memory>

#include "sim_driver/registry/domain.hpp"

namespace hbirl {

std::unique_ptr<Domain> make_onion_domain();              // onion/onion_domain.cpp
std::unique_ptr<Domain> make_gridworld_domain(int size);  // gridworld/gridworld_domain.cpp

// A simulated sensor's run (registry.cpp): the observations of every episode, one frame per step.
class SensorRun : public Simulation {
 public:
  bool camera() const override { return false; }
  const ObservedTrajectory& observed(int id) const override { return observed_[static_cast<size_t>(id)]; }

 protected:
  // The controlled run's episodes, then the demonstrations', back to back in sim time,
  // with what the sensor saw of each (`seen`: controlled first) and whether each ended
  // by entering a terminal state.
  void add_episodes(const std::vector<Trajectory>& controlled, const std::vector<Trajectory>& demonstrations,
                    std::vector<ObservedTrajectory> seen, const std::vector<char>& ended);
  std::vector<ObservedTrajectory> observed_;
};

// The controlled run's eta over all `sources`: everything on the subject.
void subject_alone(std::vector<ObservedTrajectory>& observed, int sources);

}  // namespace hbirl
