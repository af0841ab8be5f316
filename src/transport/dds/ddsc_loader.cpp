#include "transport/dds/ddsc_loader.hpp"

#include <stdexcept>

#include "util/dynamic_library.hpp"

namespace rvc::transport {

const Ddsc& ddsc() {
  // Global: CycloneDDS's own plugins resolve against it. A throw leaves it
  // unset: the next call tries again.
  static const Ddsc d = util::load_functions<std::runtime_error, Ddsc>(
      kDdscSoname, RTLD_GLOBAL, "dds: endpoints need CycloneDDS, Debian package libddsc0debian",
      [](Ddsc& t, auto set) {
#define RVC_DDSC_SET(name) set(t.name, #name);
        RVC_DDSC_FUNCTIONS(RVC_DDSC_SET)
#undef RVC_DDSC_SET
      });
  return d;
}

}  // namespace rvc::transport
