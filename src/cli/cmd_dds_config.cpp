// rvc dds-config: print the CycloneDDS XML that rvc's participants use, so
// that other DDS programs on the host (ROS 2 nodes, ddsperf, Python
// cyclonedds) can join the same loopback-pinned network through
// CYCLONEDDS_URI=file://...
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/commands.hpp"
#include "cli/transport_flags.hpp"
#include "transport/dds/dds_options.hpp"
#include "transport/output_file.hpp"

namespace rvc::cli {

Runner register_dds_config(CLI::App& app) {
  struct Cmd {
    transport::DdsOptions dds;
    std::string output = "-";
  };
  auto cmd = std::make_shared<Cmd>();
  CLI::App* sub = app.add_subcommand("dds-config", "Print the CycloneDDS XML rvc uses (for CYCLONEDDS_URI of other programs)");
  add_dds_options(*sub, cmd->dds);
  sub->add_option("--output,-o", cmd->output, "File to write (- for stdout)")->capture_default_str();
  return [cmd] {
    std::string xml = transport::dds::generated_config_xml(cmd->dds);
    std::FILE* out = stdout;
    if (cmd->output != "-") {
      try {
        out = transport::open_output_file(cmd->output, "--output");
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "rvc: %s\n", e.what());
        return static_cast<int>(kUsage);
      }
    }
    std::fputs(xml.c_str(), out);
    if (out != stdout) std::fclose(out);
    return static_cast<int>(kOk);
  };
}

}  // namespace rvc::cli
