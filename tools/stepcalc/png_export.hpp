// SVG -> PNG with rsvg-convert (Debian package librsvg2-bin), run at run time.
#pragma once
#include <string>

namespace stepnode::tools {

// Writes `svg` as a PNG to `png_path` through `rsvg-convert` on the PATH. Throws
// std::runtime_error with a clear message when the tool is missing or fails.
void write_png(const std::string& svg, const std::string& png_path);
// `svg` to `path`: a .png through write_png, anything else as the SVG text. Throws
// std::runtime_error when the file cannot be written.
void write_plot(const std::string& svg, const std::string& path);
// Whether `path` names a file --plot can write (.svg or .png).
bool plot_path_ok(const std::string& path);

}  // namespace stepnode::tools
