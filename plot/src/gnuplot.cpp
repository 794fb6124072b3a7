#include "plot/gnuplot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <vector>

extern char** environ;

namespace hbirl {

std::string gnuplot_quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string run_gnuplot(const std::string& path_stem, const std::string& data, const std::string& plot, int width,
                        int height) {
  const std::string script_path = path_stem + ".gp";
  std::ofstream script(script_path);
  const std::string size = std::to_string(width) + "," + std::to_string(height);
  script << "# Written by hbirl; run `gnuplot " << script_path << "` to redraw.\n"
         << data << "set terminal pngcairo size " << size << " noenhanced font 'sans,11'\nset output "
         << gnuplot_quoted(path_stem + ".png") << "\n"
         << plot << "set terminal svg size " << size << " noenhanced font 'sans,11' background rgb 'white'\nset output "
         << gnuplot_quoted(path_stem + ".svg") << "\n"
         << plot << "unset output\n";
  script.close();
  if (!script) return "cannot write " + script_path;
  // gnuplot SCRIPT, no shell in between (the path may hold any character); its chatter
  // on stderr goes to /dev/null.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  std::string program = "gnuplot";
  std::vector<char*> argv = {program.data(), const_cast<char*>(script_path.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  int status = -1;
  if (spawned == 0) waitpid(pid, &status, 0);
  if (spawned != 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return "gnuplot failed or is not installed (apt-get install gnuplot-nox); the script is " + script_path;
  }
  return "";
}

}  // namespace hbirl
