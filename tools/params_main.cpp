// alight-params: every parameter of a configuration file as the nodes read it, with its unit,
// constraint and meaning, from the one declaration of each parameter (issue 18).
//
//   alight-params --dump config/vehicles/pelican.yaml    # values in effect, defaults filled in
//   alight-params --defaults vehicle                     # the defaults alone
//
// The output is YAML that loads back to the same values. A bad file is exit 2 with the error
// naming the file, the full key and the value, as the nodes report it.
#include <CLI/CLI.hpp>
#include <functional>
#include <iostream>
#include <sstream>

#include "common/params.hpp"
#include "outer_loop/params.hpp"

namespace alight {
namespace {

// One top-level section of a kind of file: how to load it (validated) and dump it.
struct Section {
  std::string key;
  std::string doc;
  std::function<void(const ParamNode* root, std::ostream& out)> dump;  // root null: defaults
};

template <class P>
Section section(std::string key, std::string doc, std::function<P(const ParamNode&)> load) {
  return {key, doc, [key, load](const ParamNode* root, std::ostream& out) {
            const P p = root ? load(*root) : P{};
            out << key << ":\n";
            P::schema().dump(out, p, 2);
          }};
}

std::vector<Section> vehicle_sections() {
  return {
      section<outer_loop::OuterLoopParams>(
          "outer_loop", "position controller (paper 3.4, 4.1): alight-outer-loop",
          [](const ParamNode& r) { return outer_loop::load_params(r); }),
  };
}

int run(int argc, char** argv) {
  CLI::App app{"Every parameter of an alight configuration file, with unit and constraint"};
  std::string dump_file, defaults_kind, kind = "vehicle";
  app.add_option("--dump", dump_file, "configuration file to read and print in full");
  app.add_option("--defaults", defaults_kind, "print the defaults of a kind of file")
      ->check(CLI::IsMember({"vehicle"}));
  app.add_option("--kind", kind, "kind of the --dump file")->check(CLI::IsMember({"vehicle"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (dump_file.empty() == defaults_kind.empty()) {
    std::cerr << "alight-params: give exactly one of --dump FILE or --defaults KIND\n";
    return 2;
  }
  try {
    std::optional<ParamNode> root;
    if (!dump_file.empty()) root = ParamNode::load_file(dump_file);
    std::ostringstream out;
    out << "# " << (root ? "parameters in effect for " + dump_file : "defaults of a " + defaults_kind + " file")
        << " (alight-params)\n";
    for (const auto& s : vehicle_sections()) {
      out << "\n# " << s.doc << "\n";
      s.dump(root ? &*root : nullptr, out);
    }
    std::cout << out.str();
  } catch (const ParamError& e) {
    std::cerr << "alight-params: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace
}  // namespace alight

int main(int argc, char** argv) { return alight::run(argc, argv); }
