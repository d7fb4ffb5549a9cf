#pragma once
// The subcommands of `regolith`. Each add*Command() registers one subcommand on the app,
// with its options and a callback that runs it. A callback reports failure by throwing
// (regolith::Error and its kin for bad input, CLI::Error for usage errors); main() turns
// that into "regolith: error: ..." on stderr and a non-zero exit code.

namespace CLI {
class App;
}  // namespace CLI

namespace regolith::tools {

void addDemoCommand(CLI::App& app);
void addGenerateCommand(CLI::App& app);
void addImportCommand(CLI::App& app);
void addInfoCommand(CLI::App& app);
void addQueryCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);

}  // namespace regolith::tools
