#pragma once
// The commands `hbirl` runs in `hbirl-full`, next to it: they link OpenCV, LCM, libsodium,
// the dashboard or the domains (validate opens a domain file as the services would), whose
// loading alone took ~15 ms -- every learning command would pay it (docs/BENCHMARKS.md,
// "Start-up"). Their names and descriptions, which both show.
namespace hbirl::cli {

struct FullCommand {
  const char* name;
  const char* description;
};

inline constexpr FullCommand kValidate{
    "validate",
    "Check a problem file (or, with --domain, a domain file) and print a JSON summary (sizes,\n"
    "trajectories, steps, observations, occluded steps; a domain's names and sensor). Problems\n"
    "are reported as one line on stderr naming the field and position, with exit status 2;\n"
    "unknown keys only warn."};
inline constexpr FullCommand kExperiment{"experiment", "Reproduce the paper's experiments (runs, summary, figure)."};
inline constexpr FullCommand kRender{
    "render",
    "Render frames of the simulated onion-sorting camera (paper §Experiments B): the expert sorting\n"
    "onions with the chosen confounding elements, each frame with the blobs perception\n"
    "found, their symbol (gN: gripper region N of 20; B/D: bright/dark onion) and the\n"
    "labeller's eta for the expert. Writes PNGs to --out and a JSON list of them (with the\n"
    "true state, action and observed symbols of each frame) to stdout."};
inline constexpr FullCommand kReport{
    "report",
    "Write the dashboard's views of a recorded run (services/launch.sh --record) as a static page:\n"
    "OUT/index.html with the figures as PNG and SVG (gnuplot; each with its script), the last\n"
    "camera frame with its detections coloured by their most likely source, and OUT/state.json."};
inline constexpr FullCommand kPublish{
    "publish",
    "Stream a problem file's demonstration onto the bus exactly as a sensor would (docs/your-task.md):\n"
    "EPISODE markers, one OBSERVATIONS message per step, and GROUND_TRUTH for the trajectories marked\n"
    "\"controlled\". A live optimiser started with --domain on the same file learns what `hbirl learn\n"
    "--problem FILE` learns (with the same --eta), bit for bit. Waits for the optimiser's heartbeat first, and\n"
    "afterwards sends steps lost on the way again until the optimiser's reward."};
inline constexpr FullCommand kExport{
    "export",
    "Turn a recorded run (services/launch.sh --record) into a problem file: the domain's MDP and names,\n"
    "the demonstrations as the optimiser received them, and the observation prior it learned from (the\n"
    "controlled run's counts included). `hbirl learn --problem OUT` then learns the live run's theta bit\n"
    "for bit (and prints the learned observation model and eta); `hbirl posterior --weights W` shows each\n"
    "step's posterior under the prior's O and the stated eta, not the learned ones."};
inline constexpr FullCommand kKeygen{
    "keygen",
    "Write a fresh key (32 random bytes as 64 hexadecimal digits) to a new file with mode 0600: a key\n"
    "for many runs (e.g. shared with sampler workers on other machines, which then serve any run of\n"
    "it), or with --run / --run-of a key file for one run, which also names a fresh run identity.\n"
    "Services, `hbirl publish`, the dashboard and readers of a recording given a run's key file sign\n"
    "every message for that run and drop those not signed with the key for it: a key shared by many\n"
    "runs does not let one run's messages into another. services/launch.sh writes one per run."};
inline constexpr FullCommand kFullCommands[] = {kValidate, kExperiment, kRender, kReport, kPublish, kExport, kKeygen};

}  // namespace hbirl::cli
