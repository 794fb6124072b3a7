#pragma once
// Figures drawn by gnuplot (Debian's gnuplot-nox), for the experiments and the report:
// a script written next to the figure, so anyone can redraw it.
#include <string>

namespace hbirl {

// A gnuplot single-quoted string (a quote inside is written twice).
std::string gnuplot_quoted(const std::string& s);

// Any figure: writes <stem>.gp -- `data` (e.g. inline data blocks and settings) once, then
// `plot` drawn to <stem>.png and again to <stem>.svg -- and runs gnuplot on it. Returns
// as draw_figure does.
std::string run_gnuplot(const std::string& path_stem, const std::string& data, const std::string& plot, int width,
                        int height);

}  // namespace hbirl
