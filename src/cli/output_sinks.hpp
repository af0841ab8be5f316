// Opening the outputs of a participant (monitor verdicts, sync sets) and
// waiting for their subscribers first: a payload written before a subscriber
// has matched is lost (volatile QoS), and the first one follows the first
// input message at once.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "transport/endpoint.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

// Opens every URI; with wait_subscribers > 0 waits for that many subscribers
// on each network output. Returns 0, or the exit status to end with (none
// matched in time; the reason is printed, with how this publisher is found).
int open_outputs(const std::vector<std::string>& uris, const transport::TransportOptions& transports,
                 size_t wait_subscribers, double wait_timeout, const char* who,
                 std::vector<std::unique_ptr<transport::Sink>>& sinks);

// mcap:PATH?inputs=1 copies a bag's messages only: with another input (JSON
// lines, live topics) nothing would be copied, so the run is refused instead.
// Returns 0, or kUsage after printing why.
int refuse_input_copies(const std::vector<std::string>& outputs, const std::string& input);

// The file an output writes (file:PATH, a plain path, mcap:PATH, sqlite:PATH,
// a spool file), or "" (stdout, a topic, a PostgreSQL database).
std::string written_file(const std::string& uri);

// Two outputs of one run (verdicts, --stats-output, --diagnostics, the
// results database and its spool) that name one file would overwrite each
// other (an MCAP file that is no longer MCAP, verdict lines lost): refused at
// start, before anything is written. One file: the same inode when it exists
// (hard links, symlinks, ./v.mcap and v.mcap), else the same path once made
// absolute with its existing part resolved. Each target is {option, uri}.
// Returns 0, or kUsage after printing both.
int refuse_shared_files(const std::vector<std::pair<std::string, std::string>>& targets);

}  // namespace rvc::cli
