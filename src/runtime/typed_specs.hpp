// Properties over typed (ROS 2) messages: every field a property tests must
// exist in the message type, and a bare word compared with a numeric field
// ({gear.report == REVERSE}) names a constant of the message that holds the
// field. Checked once, before the first message, so a typo is a spec error
// with its column rather than a field that is silently never present.
#pragma once

#include <vector>

#include "engine/checker.hpp"
#include "msg/msg_types.hpp"

namespace rvc::runtime {

// Throws spec::SpecError (naming the property, the column, the fields or
// constants there are) for a field the type lacks or an unknown constant;
// replaces constants by their values in the checker's atom table.
void bind_message_type(engine::Checker& checker, const std::vector<engine::PropertySpec>& properties,
                       const msg::MessageType& type, bool dense, const std::string& time_field);

// The same for one named input of several (`--input gear=dds:... --type
// ...`): only the tests on "input.…" are checked, against `type`, and bound
// in `atoms`, the input's own table, where they are held without the
// "input." prefix.
void bind_message_type(engine::AtomTable& atoms, const std::vector<engine::PropertySpec>& properties,
                       const msg::MessageType& type, bool dense, const std::string& time_field,
                       const std::string& input);

}  // namespace rvc::runtime
