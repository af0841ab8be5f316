// CycloneDDS (libddsc), loaded when the first dds: endpoint is made rather
// than at every start of rvc: linked normally, libddsc and the iceoryx
// libraries it pulls in cost every `rvc` run about 8 M instructions of
// relocations, more than `rvc check` spends on a small file, for a library
// a file check never calls. dds/dds.h still gives the declarations, types
// and inline helpers; every function call goes through this table.
#pragma once

#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>

namespace rvc::transport {

// The soname, read from the library at configure time (cmake/RuntimeLibraries.cmake).
inline constexpr const char* kDdscSoname = RVC_DDSC_SONAME;

#define RVC_DDSC_FUNCTIONS(X) \
  X(dds_create_domain) X(dds_create_guardcondition) X(dds_create_listener) X(dds_create_participant) \
  X(dds_create_publisher) X(dds_create_qos) X(dds_create_readcondition) X(dds_create_reader) \
  X(dds_create_subscriber) X(dds_create_topic) X(dds_create_waitset) X(dds_create_writer) X(dds_delete) \
  X(dds_delete_listener) X(dds_delete_qos) X(dds_get_publication_matched_status) \
  X(dds_get_subscription_matched_status) X(dds_lset_requested_incompatible_qos) X(dds_istream_fini) X(dds_istream_init) \
  X(dds_lset_data_available) X(dds_qset_durability) X(dds_qset_durability_service) X(dds_qset_entity_name) \
  X(dds_qset_history) X(dds_qset_liveliness) X(dds_qset_partition1) X(dds_qset_reliability) X(dds_qset_resource_limits) \
  X(dds_return_loan) X(dds_set_guardcondition) X(dds_set_listener) X(dds_set_status_mask) \
  X(dds_stream_free_sample) X(dds_stream_normalize_data) X(dds_stream_read) X(dds_strretcode) X(dds_take) \
  X(dds_takecdr) X(dds_wait_for_acks) X(dds_waitset_attach) X(dds_waitset_wait) X(dds_write) \
  X(dds_write_flush)

struct Ddsc {
#define RVC_DDSC_POINTER(name) decltype(&::name) name = nullptr;
  RVC_DDSC_FUNCTIONS(RVC_DDSC_POINTER)
#undef RVC_DDSC_POINTER
};

// Loads CycloneDDS on first use (thread-safe). Throws std::runtime_error
// naming the library and what dlopen said when it is missing.
const Ddsc& ddsc();

}  // namespace rvc::transport
