// The `regolith` command: one subcommand per file (*Command.cpp), registered here.
#include <regolith/core/Error.hpp>
#include <regolith/store/Store.hpp>

#include "Commands.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <string>

namespace {

/// CLI11 takes an unknown first word for a stray argument: "A subcommand is required", and
/// with --help it prints the main help and exits 0. Name the word, in both cases, as a usage
/// error (exit code 109, CLI11's for unexpected arguments).
void refuseUnknownSubcommand(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.starts_with("-")) continue;  // the main command's options: --help
    std::string names;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
      if (sub->get_name() == word) return;
      if (!names.empty()) names += ", ";
      names += sub->get_name();
    }
    std::string message = "unknown subcommand '" + word + "', expected one of: ";
    message += names;
    throw CLI::ParseError(message, CLI::ExitCodes::ExtrasError);
  }
}

}  // namespace

int main(int argc, char** argv) try {
  regolith::store::skipHdf5ShutdownAtExit();  // no HDF5 junk after a clear error (Store.hpp)
  CLI::App app{"Regolith: planetary terrain for simulation and visualization"};
  app.name("regolith");
  app.require_subcommand(1);
  app.failure_message([](const CLI::App* failed, const CLI::Error& e) {
    // The (sub)command that was being parsed: "regolith generate victoria". CLI11 reports
    // errors on the root app, so follow the subcommands that were given.
    std::string command = "regolith";
    for (const CLI::App* a = failed; !a->get_subcommands().empty();) {
      a = a->get_subcommands().front();
      command += " " + a->get_name();
    }
    return "regolith: error: " + std::string(e.what()) + "\nRun '" + command +
           " --help' for more information.\n";
  });

  regolith::tools::addDemoCommand(app);
  regolith::tools::addGenerateCommand(app);
  regolith::tools::addImportCommand(app);
  regolith::tools::addInfoCommand(app);
  regolith::tools::addQueryCommand(app);
  regolith::tools::addRenderCommand(app);
  regolith::tools::addReportCommand(app);
#ifdef REGOLITH_HAVE_VIEW
  regolith::tools::addViewCommand(app);
#endif

  try {
    refuseUnknownSubcommand(app, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::Error& e) {
    // Usage errors print the failure message above; --help prints help and returns 0;
    // CLI::RuntimeError carries a subcommand's own exit code.
    return app.exit(e);
  }
  return 0;
} catch (const regolith::Error& e) {
  std::cerr << "regolith: error: " << e.what() << '\n';
  return 1;
} catch (const std::exception& e) {
  std::cerr << "regolith: error: " << e.what() << '\n';
  return 1;
}
