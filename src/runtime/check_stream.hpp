// `rvc check`'s run: a JSON-lines stream (a file or stdin) read in chunks
// through the same Pipeline and VerdictOutputs as `rvc monitor`.
#pragma once

#include <functional>

#include "io/json_writer.hpp"
#include "io/jsonl_reader.hpp"
#include "runtime/exit_status.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime {

// Reads `fd` to its end. Never throws for a failure while running (a read
// error, an output that cannot be written): the outcome says so and the
// reason is printed. `live`: flush verdicts after every chunk read (stdin fed
// by another program, where verdicts should show as soon as they are known).
// `tick_at_end` (dense time, --clock auto): a tick at the last stamp reports
// the last message's own verdicts (its segment has no end otherwise).
Outcome check_stream(int fd, Pipeline& pipeline, VerdictOutputs& outputs, io::ReaderOptions reader, bool live,
                     bool tick_at_end = false);

// The frame of every check run: `read` feeds the pipeline (and may note
// what it met in the outcome), then the outputs get their end-of-stream
// marker. A failure while running is printed and noted, never thrown.
// After `read`, the feed learns that the input ended (a synchronizer
// releases what it holds).
Outcome run_check(Feed& feed, VerdictOutputs& outputs, const std::function<void(Outcome&)>& read);

// The counters of a run, as the monitor's counters line has them: received,
// checked, rejected, dropped (by reason), warnings, verdicts, violations.
// rvc check --stats and a bag's run print them.
void add_run_counters(io::JsonObject& out, const Feed& feed, uint64_t verdicts);

// True if both paths name the same existing regular file (also through links,
// compared by device and inode): used to refuse writing verdicts over the
// input being read. `a` may be "-": stdin, and the file it was redirected
// from (`rvc check - -o t.jsonl < t.jsonl`).
bool same_regular_file(const std::string& a, const std::string& b);

}  // namespace rvc::runtime
