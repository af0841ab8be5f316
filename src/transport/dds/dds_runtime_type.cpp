#include "transport/dds/dds_runtime_type.hpp"

#include <dds/ddsc/dds_opcodes.h>

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
    for (const auto& p : patches_) {
      // A signed 16-bit jump: a nested type already emitted for an earlier
      // field (Time inside two different messages) lies behind the caller.
      const auto jump = static_cast<int64_t>(start_.at(p.target)) - static_cast<int64_t>(p.insn);
      ops_[p.word] = (p.insn_len << 16) | (static_cast<uint32_t>(jump) & 0xffffu);
    }
    return ops_;
  }
  uint32_t instructions() const { return instructions_; }

 private:
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
      for (size_t i = 0; i < m.fields.size(); ++i) emit_field(m.fields[i].type, offsets[i]);
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
};

}  // namespace

std::string ros2_dds_type_name(const MessageType& type) {
  return type.package + "::msg::dds_::" + type.name + "_";
}

RuntimeTopicType::RuntimeTopicType(const MessageType& type) : type_name_(ros2_dds_type_name(type)) {
  Layouts layouts;
  OpsBuilder builder(layouts);
  ops_ = builder.build(type);
  const Layout l = layouts.of_message(type);
  size_ = l.size;
  align_ = l.align;
  // No XTypes type information: peers match on the type name, as with
  // rmw_cyclonedds. NO_OPTIMIZE: CycloneDDS never memcpys a sample on the
  // strength of this layout (rvc reads and writes serialized data only).
  desc_.reset(new dds_topic_descriptor_t{size_, align_, DDS_TOPIC_NO_OPTIMIZE, 0u, type_name_.c_str(), nullptr,
                                         builder.instructions(), ops_.data(), "", {nullptr, 0}, {nullptr, 0}, 0u});
}

}  // namespace rvc::transport::dds
