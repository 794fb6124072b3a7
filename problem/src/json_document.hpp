#pragma once
// A problem or domain file's text made into the JSON document its readers walk (JsonNode),
// building only what they will read (docs/RELIABILITY.md, "The command line"):
//  - a key the format does not know keeps its name, so that the reader warns about it, but
//    its value (which may be most of the file) is never built;
//  - a list of tuples (mdp.transitions' [s, a, s', p]) is checked element by element as it
//    is read: an element of the wrong shape, or a repeated one where the format forbids
//    repeats, is refused there with the message the reader gives, not after the rest of
//    the file has been built;
//  - a key that appears twice in one object is refused (JSON leaves duplicates to the
//    reader; nlohmann keeps the last, which silently hid mistakes).
// It builds the document with nlohmann's SAX interface rather than its parse callback,
// whose end of every object scans its parent's elements (quadratic in a trajectory's steps).
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace hbirl::detail {

// One kind of list of tuples.
struct TupleList {
  size_t size = 0;         // entries per tuple
  const char* shape = "";  // "[state, action, next_state, probability]", for messages
  size_t key_length = 0;   // the first key_length entries may not repeat (0: they may)
  const char* what = "";   // "transition": "duplicate transition (also given at index 3)"
};

inline constexpr TupleList kTransitionTuple{4, "[state, action, next_state, probability]", 3, "transition"};
inline constexpr TupleList kStartTuple{2, "[state, probability]", 1, "start state"};
inline constexpr TupleList kFeatureTuple{4, "[state, action, feature, value]", 3, "feature entry"};
inline constexpr TupleList kImpossibleTuple{2, "[state, action]"};
inline constexpr TupleList kSubjectAlphaTuple{4, "[state, action, symbol, alpha]"};
inline constexpr TupleList kConfounderAlphaTuple{3, "[confounder, symbol, alpha]"};
inline constexpr TupleList kEndAlphaTuple{3, "[terminal_state, symbol, alpha]"};
inline constexpr TupleList kTruthTuple{2, "[state, action]"};
inline constexpr TupleList kSubjectObservationTuple{4, "[state, action, symbol, probability]"};
inline constexpr TupleList kConfounderObservationTuple{3, "[element, symbol, probability]"};
inline constexpr TupleList kEndObservationTuple{3, "[terminal_state, symbol, probability]"};

// What the readers know of a value. Where the value has another type than its shape
// expects, the shape is not applied and the reader reports the type.
class JsonShape {
 public:
  // Any value, built whole.
  static JsonShape any() { return JsonShape(Kind::kAny); }
  // A known key whose value no reader reads (a domain file's "demonstration"): not built.
  static JsonShape unread() { return JsonShape(Kind::kUnread); }
  // An object with these keys (each with its value's shape; nullptr: any value).
  static JsonShape object(std::vector<std::pair<std::string, const JsonShape*>> members);
  // An array of elements of one shape, or of tuples.
  static JsonShape list(const JsonShape& element);
  static JsonShape list(const TupleList& tuple);

  // The keys of an object, for JsonNode::check_keys.
  const std::vector<std::string>& keys() const { return keys_; }

 private:
  enum class Kind { kAny, kUnread, kObject, kList };
  explicit JsonShape(Kind kind) : kind_(kind) {}
  friend class DocumentBuilder;

  Kind kind_;
  std::vector<std::string> keys_;         // kObject
  std::vector<const JsonShape*> values_;  // kObject: the shape of keys_[i]'s value
  const JsonShape* element_ = nullptr;    // kList
  const TupleList* tuple_ = nullptr;      // kList of tuples
};

// The document `text` holds, built as `shape` says; malformed JSON is InputError("",
// "malformed JSON: ..."), anything refused while reading an InputError naming its place.
nlohmann::json parse_json_text(const std::string& text, const JsonShape& shape);

}  // namespace hbirl::detail
