#pragma once
// One validation of each message type that has rules beyond its encoding, the same for
// every reader -- the optimiser's data set, the dashboard, a recording's readers: what a
// message must be whatever the domain. Typed subscribe() (typed.hpp) calls it before the
// handler, so no reader can skip it; a reader adds only what its own job needs (the
// domain's alphabet, what the dashboard can draw). Each throws InputError naming the field.
// Declare every validate() here: typed subscribe finds those declared before it (messages
// are in namespace hbirl, these in hbirl::services, so argument-dependent lookup does not).
#include "hbirl/observations_t.hpp"

namespace hbirl::services {

// Frames of a step and steps of an episode a message may name.
constexpr int kMaxSteps = 100000;         // per episode
constexpr int kMaxFramesPerStep = 10000;  // e.g. 60 s steps at 120 fps

// At least one symbol and one source; episode, step and frame in range; every symbol in
// the alphabet; every eta a distribution (normalise_eta's tolerance); contexts none or one
// per observation, each in [0, kMaxContexts).
void validate(const hbirl::observations_t& m);

}  // namespace hbirl::services
