#include "json_document.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include "learner/input_error.hpp"
#include "problem/json_node.hpp"

namespace hbirl::detail {

JsonShape JsonShape::object(std::vector<std::pair<std::string, const JsonShape*>> members) {
  JsonShape shape(Kind::kObject);
  for (auto& [key, value] : members) {
    shape.keys_.push_back(std::move(key));
    shape.values_.push_back(value);
  }
  return shape;
}

JsonShape JsonShape::list(const JsonShape& element) {
  JsonShape shape(Kind::kList);
  shape.element_ = &element;
  return shape;
}

JsonShape JsonShape::list(const TupleList& tuple) {
  JsonShape shape(Kind::kList);
  shape.tuple_ = &tuple;
  return shape;
}

using Json = nlohmann::json;

namespace {

// The first few entries of a tuple as non-negative ints, when they are (any other tuple
// is left to the reader, which names what is wrong with it).
using TupleKey = std::array<uint32_t, 3>;

bool tuple_key(const Json& tuple, size_t length, TupleKey& key) {
  key = {0, 0, 0};
  for (size_t i = 0; i < length; ++i) {
    const Json& v = tuple[i];
    double x = -1.0;
    if (v.is_number_unsigned()) {
      x = static_cast<double>(std::min<uint64_t>(v.get<uint64_t>(), uint64_t{1} << 32));
    } else if (v.is_number()) {
      x = v.get<double>();  // an integer, or a float the reader reads as one (1.0)
    }
    if (!(x >= 0.0 && x <= std::numeric_limits<int>::max() && x == std::floor(x))) return false;
    key[i] = static_cast<uint32_t>(x);
  }
  return true;
}

}  // namespace

// The keys of a tuple list read so far, each with the index it was first given at: open
// addressing in a flat table (16 bytes a slot, a quarter to a half of them in use), a
// fraction of what the list's own elements take (~130 bytes each). Needed only once a
// list's keys stop increasing (DocumentBuilder::check_element).
class FirstIndex {
 public:
  // The index `key` was first given at; `index` (now recorded) when it is new.
  uint32_t insert(const TupleKey& key, uint32_t index) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    Slot& slot = find(key);
    if (slot.index == kFree) {
      slot = {key, index};
      ++used_;
    }
    return slot.index;
  }

 private:
  static constexpr uint32_t kFree = std::numeric_limits<uint32_t>::max();
  struct Slot {
    TupleKey key;
    uint32_t index = kFree;
  };

  static uint64_t mix(uint64_t x) {  // splitmix64's finaliser
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
  }

  Slot& find(const TupleKey& key) {
    const uint64_t h = mix(mix((uint64_t{key[0]} << 32 | key[1]) + 0x9E3779B97F4A7C15ULL) ^ key[2]);
    const size_t mask = slots_.size() - 1;
    for (size_t i = static_cast<size_t>(h) & mask;; i = (i + 1) & mask) {
      if (slots_[i].index == kFree || slots_[i].key == key) return slots_[i];
    }
  }

  void grow() {
    std::vector<Slot> old(std::max<size_t>(16, 2 * slots_.size()));
    old.swap(slots_);
    for (const Slot& s : old) {
      if (s.index != kFree) find(s.key) = s;
    }
  }

  std::vector<Slot> slots_;
  size_t used_ = 0;
};

// nlohmann's SAX interface, building the document as json_sax_dom_parser does, but only
// the parts a reader will look at (json_document.hpp).
class DocumentBuilder {
 public:
  explicit DocumentBuilder(const JsonShape& shape) : root_shape_(&shape) {}
  Json take() { return std::move(root_); }

  bool null() { return scalar(Json(nullptr)); }
  bool boolean(bool v) { return scalar(Json(v)); }
  bool number_integer(Json::number_integer_t v) { return scalar(Json(v)); }
  bool number_unsigned(Json::number_unsigned_t v) { return scalar(Json(v)); }
  bool number_float(Json::number_float_t v, const std::string&) { return scalar(Json(v)); }
  bool string(std::string& v) { return scalar(Json(std::move(v))); }
  bool binary(Json::binary_t& v) { return scalar(Json(std::move(v))); }
  bool start_object(size_t) { return open(Json::value_t::object); }
  bool start_array(size_t) { return open(Json::value_t::array); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }
  bool key(std::string& key);
  template <typename Exception>
  bool parse_error(size_t, const std::string&, const Exception& e) {
    throw e;
  }

 private:
  using Kind = JsonShape::Kind;
  static constexpr size_t kMaxDepth = 64;

  // A container being read.
  struct Open {
    Json* value;
    const JsonShape* shape;  // nullptr: anything (or a shape of another type)
    const std::string* key;  // its key in the enclosing object; nullptr in an array
    size_t index;            // its index in the enclosing array
    // A tuple list with keys: while they increase (as in a file a program wrote) none can
    // repeat and only the last is kept; after that, every key in `seen`.
    bool keyed = false;
    bool any = false;  // a key read yet
    TupleKey last{};
    std::unique_ptr<FirstIndex> seen;
  };

  // Where the next value goes, and what is known of it; false when it is not built.
  bool next(const JsonShape*& shape, const std::string*& key, size_t& index) const;
  Json* place(Json&& value);
  bool scalar(Json&& value);
  bool open(Json::value_t type);
  bool close();
  void check_element(Open& list, const Json& element, size_t index);
  std::string path(size_t index) const;  // of element `index` of the innermost container

  Json root_;
  const JsonShape* root_shape_;
  std::vector<Open> stack_;
  size_t skipping_ = 0;      // how deep inside a value that is not built
  bool skip_value_ = false;  // the value of the key just read is not built
  Json* member_ = nullptr;   // where the value of the key just read goes
  const JsonShape* member_shape_ = nullptr;
  const std::string* member_key_ = nullptr;
};

bool DocumentBuilder::key(std::string& key) {
  if (skipping_ > 0) return true;
  Open& top = stack_.back();
  auto [slot, added] = top.value->get_ref<Json::object_t&>().emplace(std::move(key), nullptr);
  if (!added)
    throw InputError(path(0).empty() ? slot->first : path(0) + "." + slot->first, "appears twice in the same object");
  member_ = &slot->second;
  member_key_ = &slot->first;
  member_shape_ = nullptr;
  skip_value_ = false;
  if (top.shape == nullptr) return true;
  const auto& keys = top.shape->keys_;
  const auto known = std::find(keys.begin(), keys.end(), slot->first);
  if (known == keys.end()) {
    skip_value_ = true;  // kept as null: the reader warns about it (or passes a comment)
    return true;
  }
  member_shape_ = top.shape->values_[static_cast<size_t>(known - keys.begin())];
  skip_value_ = member_shape_ != nullptr && member_shape_->kind_ == Kind::kUnread;
  return true;
}

bool DocumentBuilder::next(const JsonShape*& shape, const std::string*& key, size_t& index) const {
  shape = nullptr;
  key = nullptr;
  index = 0;
  if (skipping_ > 0 || skip_value_) return false;
  if (stack_.empty()) {
    shape = root_shape_;
  } else if (stack_.back().value->is_array()) {
    const Open& list = stack_.back();
    index = list.value->size();
    if (list.shape != nullptr) shape = list.shape->element_;
  } else {
    shape = member_shape_;
    key = member_key_;
  }
  return true;
}

Json* DocumentBuilder::place(Json&& value) {
  if (stack_.empty()) {
    root_ = std::move(value);
    return &root_;
  }
  Json& container = *stack_.back().value;
  if (container.is_array()) {
    auto& elements = container.get_ref<Json::array_t&>();
    elements.push_back(std::move(value));
    return &elements.back();
  }
  *member_ = std::move(value);
  return member_;
}

bool DocumentBuilder::scalar(Json&& value) {
  const JsonShape* shape = nullptr;
  const std::string* key = nullptr;
  size_t index = 0;
  if (!next(shape, key, index)) {
    skip_value_ = false;
    return true;
  }
  const Json* placed = place(std::move(value));
  if (!stack_.empty() && stack_.back().value->is_array()) check_element(stack_.back(), *placed, index);
  return true;
}

bool DocumentBuilder::open(Json::value_t type) {
  const JsonShape* shape = nullptr;
  const std::string* key = nullptr;
  size_t index = 0;
  if (!next(shape, key, index)) {
    skip_value_ = false;
    ++skipping_;
    return true;
  }
  // No problem or domain file nests deeper than 8; each level held costs ~100 bytes for
  // one byte of text.
  if (stack_.size() >= kMaxDepth) {
    const std::string here = key == nullptr ? path(index) : path(0).empty() ? *key : path(0) + "." + *key;
    throw InputError(here, "nested more than " + std::to_string(kMaxDepth) +
                               " arrays and objects deep: not a problem or domain file");
  }
  // A shape applies to a value of its type only; the reader reports any other.
  const Kind wanted = type == Json::value_t::object ? Kind::kObject : Kind::kList;
  if (shape != nullptr && shape->kind_ != wanted) shape = nullptr;
  Json* value = place(Json(type));
  const bool keyed = shape != nullptr && shape->tuple_ != nullptr && shape->tuple_->key_length > 0;
  stack_.push_back({value, shape, key, index, keyed, false, {}, nullptr});
  return true;
}

bool DocumentBuilder::close() {
  if (skipping_ > 0) {
    --skipping_;
    return true;
  }
  const Json* closed = stack_.back().value;
  const size_t index = stack_.back().index;
  stack_.pop_back();
  if (!stack_.empty() && stack_.back().value->is_array()) check_element(stack_.back(), *closed, index);
  return true;
}

// An element of a tuple list, as the reader would check it (detail::read_mdp and others).
void DocumentBuilder::check_element(Open& list, const Json& element, size_t index) {
  if (list.shape == nullptr || list.shape->tuple_ == nullptr) return;
  const TupleList& tuple = *list.shape->tuple_;
  if (!element.is_array() || element.size() != tuple.size)
    JsonNode(element, path(index)).expect_tuple(tuple.size, tuple.shape);
  TupleKey key;
  if (!list.keyed || !tuple_key(element, tuple.key_length, key)) return;
  if (list.seen == nullptr) {
    if (!list.any || key > list.last) {
      list.any = true;
      list.last = key;
      return;
    }
    list.seen = std::make_unique<FirstIndex>();  // the keys so far, from the list itself
    for (size_t i = 0; i < index; ++i) {
      TupleKey earlier;
      if (tuple_key((*list.value)[i], tuple.key_length, earlier)) list.seen->insert(earlier, static_cast<uint32_t>(i));
    }
  }
  const uint32_t first = list.seen->insert(key, static_cast<uint32_t>(index));
  if (first != index) {
    throw InputError(path(index),
                     std::string("duplicate ") + tuple.what + " (also given at index " + std::to_string(first) + ")");
  }
}

std::string DocumentBuilder::path(size_t index) const {
  std::string p;
  for (size_t i = 1; i < stack_.size(); ++i) {
    const Open& o = stack_[i];
    if (o.key != nullptr) {
      p += p.empty() ? *o.key : "." + *o.key;
    } else {
      p += "[" + std::to_string(o.index) + "]";
    }
  }
  if (!stack_.empty() && stack_.back().value->is_array()) p += "[" + std::to_string(index) + "]";
  return p;
}

nlohmann::json parse_json_text(const std::string& text, const JsonShape& shape) {
  DocumentBuilder builder(shape);
  try {
    Json::sax_parse(text, &builder);
  } catch (const Json::exception& e) {
    // "[json.exception.parse_error.101] parse error at line 2, column 5: ..." -> drop the tag.
    std::string what = e.what();
    const auto tag_end = what.find("] ");
    if (tag_end != std::string::npos) what = what.substr(tag_end + 2);
    if (e.id == 406) what += " (NaN and infinity are not JSON numbers)";  // number overflow
    throw InputError("", "malformed JSON: " + what);
  }
  return builder.take();
}

}  // namespace hbirl::detail
