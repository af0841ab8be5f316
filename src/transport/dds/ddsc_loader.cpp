#include "transport/dds/ddsc_loader.hpp"

#include <dlfcn.h>

#include <stdexcept>
#include <string>

namespace rvc::transport {
namespace {

Ddsc load() {
  void* lib = ::dlopen(kDdscSoname, RTLD_NOW | RTLD_GLOBAL);  // global: its plugins resolve against it
  if (!lib) {
    const char* why = ::dlerror();
    throw std::runtime_error(std::string("dds: endpoints need CycloneDDS (") + kDdscSoname +
                             ", Debian package libddsc0debian): " + (why ? why : "not found"));
  }
  Ddsc d;
  const char* missing = nullptr;
#define RVC_DDSC_RESOLVE(name)                                        \
  d.name = reinterpret_cast<decltype(d.name)>(::dlsym(lib, #name));   \
  if (!d.name && !missing) missing = #name;
  RVC_DDSC_FUNCTIONS(RVC_DDSC_RESOLVE)
#undef RVC_DDSC_RESOLVE
  if (missing) throw std::runtime_error(std::string(kDdscSoname) + " has no function " + missing);
  return d;  // the library stays loaded for the life of the process
}

}  // namespace

const Ddsc& ddsc() {
  static const Ddsc d = load();  // a throw leaves it unset: the next call tries again
  return d;
}

}  // namespace rvc::transport
