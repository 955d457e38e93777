#pragma once
// The source and build trees this binary was configured in, for the programs that find the
// shipped configuration, the web page or another program there (tests, benches, the launcher).
// They are compiled into one generated file (alight_build_paths) and not into every compile
// line as -D definitions, so that a second clone of the repository compiles to the same
// objects as the first and ccache serves them.

#include <string>

namespace alight::build {

// The repository's root, e.g. "/home/me/alight".
const char* source_dir();
// The build tree, e.g. "/home/me/alight/build".
const char* binary_dir();
// A program built in this tree: binary_dir() + "/bin/" + name.
std::string program(const std::string& name);

}  // namespace alight::build
