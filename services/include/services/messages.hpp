#pragma once
// One validation of each message type that has rules beyond its encoding, the same for
// every reader -- the optimiser's data set, the dashboard, a recording's readers: what a
// message must be whatever the domain. Typed subscribe() (typed.hpp) calls it before the
// handler, so no reader can skip it; a reader adds only what its own job needs (the
// domain's alphabet, what the dashboard can draw). Each throws InputError naming the field.
// Declare every validate() here: typed subscribe finds those declared before it (messages
// are in namespace hbirl, these in hbirl::services, so argument-dependent lookup does not).
#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/episode_marker_t.hpp"
#include "hbirl/estimate_t.hpp"
#include "hbirl/ground_truth_t.hpp"
#include "hbirl/observations_t.hpp"
#include "hbirl/reward_t.hpp"
#include "hbirl/stop_t.hpp"

namespace hbirl::services {

// Frames of a step and steps of an episode a message may name.
constexpr int kMaxEpisodes = 10000000;    // per run
constexpr int kMaxSteps = 100000;         // per episode
constexpr int kMaxFramesPerStep = 10000;  // e.g. 60 s steps at 120 fps
constexpr int kMaxFeatures = 100000;      // of the true weights a ground truth carries
constexpr int kMaxFrameSide = 4096;       // a camera frame's width and height, in pixels

// At least one symbol and one source; episode, step and frame in range; every symbol in
// the alphabet; every eta a distribution (normalise_eta's tolerance); contexts none or one
// per observation, each in [0, kMaxContexts).
void validate(const hbirl::observations_t& m);
// Episode, step and frame in range; png or jpeg; a size its data holds; 1x1 to
// kMaxFrameSide a side; an image whose own header states that width and height (what a
// decoder allocates for, frame_header.hpp).
void validate(const hbirl::camera_frame_t& m);
// A frame's size as a camera frame's; every blob of a known class, its centroid in the
// frame, a positive area and a dark share in [0, 1].
void validate(const hbirl::detections_t& m);
// A known kind; the episode, and for a step's marker the step, in range; frames per step
// in [1, kMaxFramesPerStep] (but END_RUN); an episode's end in [1, kMaxSteps] steps; END_RUN's
// count of episodes not negative; what was seen of the end (a known end_state not negative, an
// end alphabet in [0, kMaxEndSymbols], at most kMaxEndReports reports each in it) only on an
// END_EPISODE that ended in a terminal state.
void validate(const hbirl::episode_marker_t& m);
// Episode, step, state and action in range; at most kMaxFeatures true weights, all finite.
void validate(const hbirl::ground_truth_t& m);
// Demonstrations in [1, kMaxEpisodes]; 1 to kMaxFeatures weights, all finite; a
// log-likelihood not above 0; the confidence -1 or in [0, 1]; the ILE and its relative size
// -1 or finite and not negative; every policy entry in [0, 1].
void validate(const hbirl::estimate_t& m);
// Demonstrations in [0, kMaxEpisodes]; the confidence in [0, 1]; a reason of at most 1000
// bytes.
void validate(const hbirl::stop_t& m);
// 1 to kMaxFeatures weights, all finite; the true weights none or as many, all finite;
// every policy entry in [0, 1]; each state's action -1 (terminal) or one of the actions;
// the ILE -1 or a number >= 0.
void validate(const hbirl::reward_t& m);

}  // namespace hbirl::services
