/* rvc_mcap.h: the C ABI of the MCAP reader in rust/rvc-zenoh
 * (src/mcap_reader.rs, in librvc_zenoh.a: one Rust library per binary).
 *
 * Conventions as in rvc_zenoh.h: opaque handle, 0 or a negative code, the
 * message of a failure in rvc_zenoh_last_error(), no panic crosses.
 * C++ code uses transport::McapBag (mcap_bag.hpp) instead.
 */
#ifndef RVC_MCAP_H
#define RVC_MCAP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define RVC_MCAP_EFORMAT (-4) /* not an MCAP file, or a record whose length runs past the file */
#define RVC_MCAP_SKIPPED 2    /* a bad record was skipped (reason in rvc_zenoh_last_error()): call again */

typedef struct rvc_mcap_reader rvc_mcap_reader;

/* One message and its channel. Pointers are valid until the next
 * rvc_mcap_next or rvc_mcap_close on the same reader. */
typedef struct rvc_mcap_message {
  const char* topic;
  const char* message_encoding; /* "cdr" for ROS 2, "json", ... */
  const char* schema_name;      /* "" if the channel has no schema */
  const char* schema_encoding;  /* "ros2msg", "ros2idl", "jsonschema", ... */
  const uint8_t* schema_data;
  size_t schema_len;
  const uint8_t* data;
  size_t len;
  uint16_t channel_id;
  uint32_t sequence;
  uint64_t log_time;     /* ns */
  uint64_t publish_time; /* ns */
  uint64_t index;        /* 1-based position in the file over all topics */
} rvc_mcap_message;

/* Opens (memory-maps) the file and checks its magic. */
int rvc_mcap_open(const char* path, rvc_mcap_reader** out);
/* 1: *out holds the next message in file order; 0: end of file;
 * RVC_MCAP_SKIPPED: a record was skipped (a chunk whose CRC does not match,
 * a message on a channel never defined, ...), reading goes on at the next
 * call; < 0: reading cannot go on. */
int rvc_mcap_next(rvc_mcap_reader* reader, rvc_mcap_message* out);
void rvc_mcap_close(rvc_mcap_reader* reader);

#ifdef __cplusplus
}
#endif

#endif
