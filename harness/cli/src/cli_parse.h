#pragma once
// One argument parser for every `hpa` command (CLI11): help and parse errors are handled alike.

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/sim/gl_backend.h"

namespace hpa {

/// Parses argv[2..] (argv[1] is the command) into `app`. Returns the exit code to return at
/// once for --help (0), nothing when the command should run; a parse error (an unknown option,
/// a missing, malformed or empty value) throws InputError naming the command, so it exits 2.
inline std::optional<int> ParseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    throw InputError(app.get_name(), "", e.what());
  }
  // an option given an empty value ("--out ''") is a mistake, never a request for the default
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& value : option->results()) {
      if (value.empty()) {
        throw InputError(app.get_name(), option->get_name(),
                         "an empty value; leave the option out for its default");
      }
    }
  }
  return std::nullopt;
}

/// The longest flight-stack command a sweep or compare accepts (bytes).
constexpr size_t kMaxFlightStackBytes = 4096;

/// Why `command` cannot start a flight stack, "" when it can: blank (a shell that exits at once
/// is a mistake, not a stack), a NUL byte (it would cut the command short), or longer than
/// kMaxFlightStackBytes.
inline std::string FlightStackCommandError(const std::string& command) {
  if (command.find_first_not_of(" \t\n") == std::string::npos) {
    return "expected a shell command, got '" + command +
           "' (leave it out to fly the flight code in process)";
  }
  if (command.find('\0') != std::string::npos) return "a NUL byte in the command";
  if (command.size() > kMaxFlightStackBytes) {
    return "a command of " + std::to_string(command.size()) + " bytes, more than " +
           std::to_string(kMaxFlightStackBytes);
  }
  return "";
}

/// Why `text` is no --flight-timeout, "" when it is one: finite seconds in [0.001, 3600] (NaN
/// passes a plain range check, every comparison with it being false).
inline std::string FlightTimeoutError(const std::string& text) {
  double s = 0.0;
  if (!CLI::detail::lexical_cast(text, s) || !std::isfinite(s) || s < 0.001 || s > 3600.0) {
    return "expected seconds in [0.001, 3600], got '" + text + "'";
  }
  return "";
}

/// Adds --gl osmesa|egl (the rendered cameras' GL context) to a command's parser.
inline void AddGlOption(CLI::App& app, std::string* gl) {
  app.add_option("--gl", *gl,
                 "GL context of the rendered cameras: osmesa (default, CPU) or egl (headless "
                 "GPU on cluster nodes)")
      ->check([](const std::string& value) {
        try {
          sim::ParseGlBackend(value);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      });
}

/// The back end of a --gl value; InputError naming --gl and the value for a bad one.
inline sim::GlBackend ParseGlOption(const std::string& gl) {
  try {
    return sim::ParseGlBackend(gl);
  } catch (const std::invalid_argument& e) {
    throw InputError("", "--gl", e.what());
  }
}

}  // namespace hpa
