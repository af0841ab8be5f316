#include "transport/dds/dds_runtime_type.hpp"

#include <dds/ddsc/dds_opcodes.h>

#include <deque>
#include <map>
#include <stdexcept>

namespace rvc::transport::dds {
namespace {

using msg::ArrayKind;
using msg::FieldType;
using msg::MessageType;
using msg::Prim;

// The opcodes as plain integers (they are distinct enums in dds_opcodes.h).
constexpr uint32_t kAdr = DDS_OP_ADR, kRts = DDS_OP_RTS, kExt = DDS_OP_TYPE_EXT, kArr = DDS_OP_TYPE_ARR,
                   kSeq = DDS_OP_TYPE_SEQ, kBsq = DDS_OP_TYPE_BSQ, k1By = DDS_OP_TYPE_1BY;

struct Layout {
  uint32_t size = 0, align = 1;
};

uint32_t round_up(uint32_t n, uint32_t align) { return (n + align - 1) / align * align; }

// The C layout idlc gives each IDL type on LP64 (the sample struct the ops address).
class Layouts {
 public:
  Layout of_message(const MessageType& m) {
    if (auto it = messages_.find(&m); it != messages_.end()) return it->second;
    Layout l;
    if (m.fields.empty()) {
      l = {1, 1};  // rosidl adds `uint8 structure_needs_at_least_one_member`
    } else {
      for (const auto& f : m.fields) {
        const Layout fl = of_field(f.type);
        l.size = round_up(l.size, fl.align) + fl.size;
        l.align = std::max(l.align, fl.align);
      }
      l.size = round_up(l.size, l.align);
    }
    messages_[&m] = l;
    return l;
  }

  // Offsets of a message's fields in its struct.
  std::vector<uint32_t> offsets(const MessageType& m) {
    std::vector<uint32_t> out;
    uint32_t at = 0;
    for (const auto& f : m.fields) {
      const Layout fl = of_field(f.type);
      at = round_up(at, fl.align);
      out.push_back(at);
      at += fl.size;
    }
    return out;
  }

  Layout of_element(const FieldType& t) {
    switch (t.prim) {
      case Prim::Bool: case Prim::Byte: case Prim::Char: case Prim::Int8: case Prim::UInt8: return {1, 1};
      case Prim::Int16: case Prim::UInt16: return {2, 2};
      case Prim::Int32: case Prim::UInt32: case Prim::Float32: return {4, 4};
      case Prim::Int64: case Prim::UInt64: case Prim::Float64: return {8, 8};
      case Prim::String: return t.string_bound ? Layout{t.string_bound + 1, 1} : Layout{8, 8};  // char[N+1] / char*
      case Prim::Message: return of_message(*t.message);
      case Prim::WString: break;
    }
    throw std::invalid_argument("dds: wstring fields are not supported");
  }

  Layout of_field(const FieldType& t) {
    const Layout e = of_element(t);
    switch (t.array) {
      case ArrayKind::None: return e;
      case ArrayKind::Fixed: return {e.size * t.array_size, e.align};
      case ArrayKind::Bounded:
      case ArrayKind::Unbounded: return {24, 8};  // dds_sequence_t: _maximum, _length, _buffer, _release
    }
    return e;
  }

 private:
  std::map<const MessageType*, Layout> messages_;
};

// The type part of an op for a primitive, as a top-level type (<< 16) or as
// the subtype of a sequence/array (<< 8), with its signed/float flags.
uint32_t value_code(const FieldType& t) {
  switch (t.prim) {
    case Prim::Bool: return DDS_OP_VAL_BLN;
    case Prim::Byte: case Prim::Char: case Prim::UInt8: case Prim::Int8: return DDS_OP_VAL_1BY;
    case Prim::Int16: case Prim::UInt16: return DDS_OP_VAL_2BY;
    case Prim::Int32: case Prim::UInt32: case Prim::Float32: return DDS_OP_VAL_4BY;
    case Prim::Int64: case Prim::UInt64: case Prim::Float64: return DDS_OP_VAL_8BY;
    case Prim::String: return t.string_bound ? DDS_OP_VAL_BST : DDS_OP_VAL_STR;
    case Prim::Message: return DDS_OP_VAL_STU;
    case Prim::WString: break;
  }
  throw std::invalid_argument("dds: wstring fields are not supported");
}

uint32_t flags(const FieldType& t) {
  switch (t.prim) {
    case Prim::Int8: case Prim::Int16: case Prim::Int32: case Prim::Int64: return DDS_OP_FLAG_SGN;
    case Prim::Float32: case Prim::Float64: return DDS_OP_FLAG_FP;
    default: return 0;
  }
}

// Emits one block of ops per message type (the top-level type first, nested
// types after it) and patches the jumps to
// nested types once every block's place is known. Jumps count words from
// the referring instruction; m_nops counts instructions.
class OpsBuilder {
 public:
  explicit OpsBuilder(Layouts& layouts) : layouts_(layouts) {}

  std::vector<uint32_t> build(const MessageType& top) {
    order(top);
    for (const MessageType* m : queue_) emit_block(*m);
    emit_keys(top);
    for (const auto& p : patches_) {
      // A signed 16-bit jump: a nested type already emitted for an earlier
      // field (Time inside two different messages) lies behind the caller.
      const auto jump = static_cast<int64_t>(start_.at(p.target)) - static_cast<int64_t>(p.insn);
      ops_[p.word] = (p.insn_len << 16) | (static_cast<uint32_t>(jump) & 0xffffu);
    }
    return ops_;
  }
  uint32_t instructions() const { return instructions_; }
  const std::vector<dds_key_descriptor_t>& keys() const { return keys_; }
  uint32_t key_flags() const { return key_flags_; }

 private:
  // Keys as idlc writes them: the key member's op gets FLAG_KEY and FLAG_MU,
  // and after the last block one KOF op per key holds the index of that
  // member's op; the key descriptor points at its KOF op. Only top-level
  // primitive and string members (what #pragma keylist and @key give in
  // data types); a key of 16 bytes or less (no strings) is "fixed".
  void emit_keys(const MessageType& top) {
    uint32_t xcdr1 = 0, xcdr2 = 0;
    bool fixed = true;
    for (size_t k = 0; k < top.keys.size(); ++k) {
      size_t i = 0;
      while (i < top.fields.size() && top.fields[i].name != top.keys[k]) ++i;
      if (i == top.fields.size()) throw std::invalid_argument("dds: key '" + top.keys[k] + "' is no member of " + top.full_name());
      const FieldType& t = top.fields[i].type;
      if (t.prim == Prim::Message || t.array != ArrayKind::None)
        throw std::invalid_argument("dds: key '" + top.keys[k] + "' of " + top.full_name() +
                                    ": only primitive and string members can be keys");
      ops_[top_insn_[i]] |= DDS_OP_FLAG_KEY | DDS_OP_FLAG_MU;
      key_names_.push_back(top.keys[k]);
      keys_.push_back({nullptr, static_cast<uint32_t>(ops_.size()), static_cast<uint32_t>(k)});
      ops_.insert(ops_.end(), {static_cast<uint32_t>(DDS_OP_KOF) | 1u, static_cast<uint32_t>(top_insn_[i])});
      const uint32_t size = static_cast<uint32_t>(msg::prim_size(t.prim));
      if (size == 0) fixed = false;
      xcdr1 = round_up(xcdr1, size ? size : 1) + size;
      xcdr2 = round_up(xcdr2, size > 4 ? 4 : (size ? size : 1)) + size;
    }
    for (size_t k = 0; k < keys_.size(); ++k) keys_[k].m_name = key_names_[k].c_str();
    if (!top.keys.empty() && fixed) {
      if (xcdr1 <= 16) key_flags_ |= DDS_TOPIC_FIXED_KEY;
      if (xcdr2 <= 16) key_flags_ |= DDS_TOPIC_FIXED_KEY_XCDR2;
    }
  }

  struct Patch {
    size_t word, insn;
    uint32_t insn_len;
    const MessageType* target;
  };

  // Blocks in idlc's order: depth first, each type followed by the types it
  // uses first (the oracle test compares the ops word for word).
  void order(const MessageType& m) {
    for (auto* q : queue_)
      if (q == &m) return;
    queue_.push_back(&m);
    for (const auto& f : m.fields)
      if (f.type.prim == Prim::Message) order(*f.type.message);
  }

  void jump_to(const MessageType* m, size_t insn, uint32_t insn_len) {
    patches_.push_back({ops_.size(), insn, insn_len, m});
    ops_.push_back(0);
  }

  void emit_block(const MessageType& m) {
    start_[&m] = ops_.size();
    if (m.fields.empty()) {
      ops_.insert(ops_.end(), {kAdr | k1By, 0u});
      ++instructions_;
    } else {
      const auto offsets = layouts_.offsets(m);
      for (size_t i = 0; i < m.fields.size(); ++i) {
        if (&m == queue_.front()) top_insn_.push_back(ops_.size());
        emit_field(m.fields[i].type, offsets[i]);
      }
    }
    ops_.push_back(kRts);
    ++instructions_;
  }

  void emit_field(const FieldType& t, uint32_t offset) {
    ++instructions_;
    const size_t insn = ops_.size();
    const uint32_t v = value_code(t);
    const bool stu = t.prim == Prim::Message, bst = v == DDS_OP_VAL_BST;
    switch (t.array) {
      case ArrayKind::None:
        if (stu) {
          ops_.insert(ops_.end(), {kAdr | kExt, offset});
          jump_to(t.message, insn, 3);
        } else {
          ops_.insert(ops_.end(), {kAdr | (v << 16) | flags(t), offset});
          if (bst) ops_.push_back(t.string_bound + 1);
        }
        return;
      case ArrayKind::Fixed:
        ops_.insert(ops_.end(), {kAdr | kArr | (v << 8) | flags(t), offset, t.array_size});
        if (stu) {
          jump_to(t.message, insn, 5);
          ops_.push_back(layouts_.of_element(t).size);
        } else if (bst) {
          ops_.insert(ops_.end(), {0u, t.string_bound + 1});
        }
        return;
      case ArrayKind::Unbounded:
      case ArrayKind::Bounded: {
        const bool bounded = t.array == ArrayKind::Bounded;
        ops_.insert(ops_.end(), {kAdr | (bounded ? kBsq : kSeq) | (v << 8) | flags(t), offset});
        if (bounded) ops_.push_back(t.array_size);
        if (stu) {
          ops_.push_back(layouts_.of_element(t).size);
          jump_to(t.message, insn, bounded ? 5 : 4);
        } else if (bst) {
          ops_.push_back(t.string_bound + 1);
        }
        return;
      }
    }
  }

  Layouts& layouts_;
  std::vector<uint32_t> ops_;
  std::vector<const MessageType*> queue_;
  std::map<const MessageType*, size_t> start_;
  std::vector<Patch> patches_;
  uint32_t instructions_ = 0;
  std::vector<size_t> top_insn_;  // word index of each top-level member's op
  std::vector<dds_key_descriptor_t> keys_;
  std::deque<std::string> key_names_;  // stable addresses for m_name
  uint32_t key_flags_ = 0;
};

}  // namespace

std::string ros2_dds_type_name(const MessageType& type) {
  if (!type.idl_name.empty()) return type.idl_name;  // a plain DDS IDL type keeps its own name
  return type.package + "::" + type.kind + "::dds_::" + type.name + "_";  // pkg::srv::dds_::X_Request_ too
}

RuntimeTopicType::RuntimeTopicType(const MessageType& type) : type_name_(ros2_dds_type_name(type)) {
  Layouts layouts;
  OpsBuilder builder(layouts);
  ops_ = builder.build(type);
  key_names_.assign(builder.keys().size(), {});
  keys_ = builder.keys();
  for (size_t k = 0; k < keys_.size(); ++k) {
    key_names_[k] = keys_[k].m_name;
    keys_[k].m_name = key_names_[k].c_str();
  }
  const Layout l = layouts.of_message(type);
  size_ = l.size;
  align_ = l.align;
  // No XTypes type information: peers match on the type name, as with
  // rmw_cyclonedds. NO_OPTIMIZE: CycloneDDS never memcpys a sample on the
  // strength of this layout (rvc reads and writes serialized data only).
  desc_.reset(new dds_topic_descriptor_t{size_, align_, DDS_TOPIC_NO_OPTIMIZE | builder.key_flags(),
                                         static_cast<uint32_t>(keys_.size()), type_name_.c_str(),
                                         keys_.empty() ? nullptr : keys_.data(),
                                         builder.instructions(), ops_.data(), "", {nullptr, 0}, {nullptr, 0}, 0u});
}

}  // namespace rvc::transport::dds
