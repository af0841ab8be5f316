#include "cli/transport_flags.hpp"

namespace rvc::cli {

void add_transport_options(CLI::App& app, transport::TransportOptions& options) {
#ifdef RVC_HAVE_ZENOH
  add_zenoh_options(app, options.zenoh);
#endif
#ifdef RVC_HAVE_DDS
  add_dds_options(app, options.dds);
#endif
  (void)app;
  (void)options;
}

}  // namespace rvc::cli
