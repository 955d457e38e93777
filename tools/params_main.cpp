// alight-params: every parameter of a configuration file as the nodes read it, with its meaning,
// constraint and unit, from the one declaration of each parameter.
//
//   alight-params --dump config/vehicles/pelican.yaml              # values in effect
//   alight-params --dump config/scenarios/ingress.yaml --kind scenario
//   alight-params --defaults camera                                 # the defaults alone
//   alight-params --check config/scenarios/*.yaml --kind scenario   # read each, print nothing
//
// Kinds: vehicle (the default), scenario, camera, station, mocap, autopilot. The output is YAML
// that loads back to the same values. A bad file is exit 2 with the error naming the file, the full
// key and the value, as the nodes report it.
#include <CLI/CLI.hpp>
#include <iostream>
#include <string>
#include <vector>

#include "common/params.hpp"
#include "tools/param_dump.hpp"

int main(int argc, char** argv) {
  using alight::tools::param_file_kinds;
  CLI::App app{"Every parameter of an alight configuration file, with unit and constraint"};
  std::string dump_file, defaults_kind, kind = "vehicle";
  std::vector<std::string> check_files;
  app.add_option("--dump", dump_file, "configuration file to read and print in full");
  app.add_option("--check", check_files,
                 "configuration files to read as the nodes do, printing only how many were read "
                 "(exit 2 at the first bad one, naming it)");
  app.add_option("--defaults", defaults_kind, "print the defaults of a kind of file")
      ->check(CLI::IsMember(param_file_kinds()));
  app.add_option("--kind", kind, "kind of the --dump or --check files")
      ->check(CLI::IsMember(param_file_kinds()));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (int(!dump_file.empty()) + int(!defaults_kind.empty()) + int(!check_files.empty()) != 1) {
    std::cerr << "alight-params: give exactly one of --dump FILE, --check FILE... or --defaults "
                 "KIND\n";
    return 2;
  }
  try {
    if (!check_files.empty()) {
      // One process for many files: a program's start-up costs more than reading one.
      for (const auto& file : check_files) alight::tools::dump_params(kind, file);
      std::cout << check_files.size() << " " << kind << " files read\n";
      return 0;
    }
    std::cout << alight::tools::dump_params(dump_file.empty() ? defaults_kind : kind, dump_file);
  } catch (const alight::ParamError& e) {
    std::cerr << "alight-params: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
