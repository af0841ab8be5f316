// `rvc check`'s run: a JSON-lines stream (a file or stdin) read in chunks
// through the same Pipeline and VerdictOutputs as `rvc monitor`.
#pragma once

#include <functional>

#include "io/jsonl_reader.hpp"
#include "runtime/exit_status.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime {

// Reads `fd` to its end. Never throws for a failure while running (a read
// error, an output that cannot be written): the outcome says so and the
// reason is printed. `live`: flush verdicts after every chunk read (stdin fed
// by another program, where verdicts should show as soon as they are known).
Outcome check_stream(int fd, Pipeline& pipeline, VerdictOutputs& outputs, io::ReaderOptions reader, bool live);

// The frame of every check run: `read` feeds the pipeline (and may note
// what it met in the outcome), then the outputs get their end-of-stream
// marker. A failure while running is printed and noted, never thrown.
// After `read`, the feed learns that the input ended (a synchronizer
// releases what it holds).
Outcome run_check(Feed& feed, VerdictOutputs& outputs, const std::function<void(Outcome&)>& read);

// True if both paths name the same existing regular file (also through links):
// used to refuse writing verdicts over the input being read.
bool same_regular_file(const std::string& a, const std::string& b);

}  // namespace rvc::runtime
