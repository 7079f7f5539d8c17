// The JSON document of a scene, built by a handler of nlohmann's SAX interface: each value is
// moved into its place as it is parsed (the object or array open on top of a stack, or the
// root), and a key is inserted into its object's member map, whose insertion reports a key that
// is already there. Each event costs O(1) plus O(log m) for a key of an object of m members, so a
// load is linear in the text (up to the log of the widest object); nlohmann's callback parser,
// used before, rescanned the parent after every object and made big scenes quadratic.
#include "json_parser.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace seiche::detail {

namespace {

class SceneDocumentBuilder {
 public:
  explicit SceneDocumentBuilder(const std::string& file) : file_(&file) {}

  Json take_document() { return std::move(root_); }

  // The SAX interface (nlohmann::json_sax): each returns true to go on parsing.
  bool null() { return add(Json(nullptr)); }
  bool boolean(bool value) { return add(Json(value)); }
  bool number_integer(Json::number_integer_t value) { return add(Json(value)); }
  bool number_unsigned(Json::number_unsigned_t value) { return add(Json(value)); }
  bool number_float(Json::number_float_t value, const Json::string_t& /*literal*/) { return add(Json(value)); }
  bool string(Json::string_t& value) { return add(Json(std::move(value))); }
  bool binary(Json::binary_t& value) { return add(Json::binary(std::move(value))); }

  bool start_object(std::size_t /*elements, unknown for text*/) { return open(Json::value_t::object); }
  bool start_array(std::size_t /*elements, unknown for text*/) { return open(Json::value_t::array); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(Json::string_t& key) {
    Open& top = open_.back();
    auto& members = top.node->get_ref<Json::object_t&>();
    const auto [member, inserted] = members.try_emplace(std::move(key));
    top.key = &member->first;
    top.slot = &member->second;
    if (!inserted) fail(*file_, path(), "duplicate key; a key may appear only once per object");
    return true;
  }

  // Malformed text: rethrown with its own type (parse_error with its byte offset, or
  // out_of_range for a number beyond a double), for parse_json to turn into a SceneError.
  template <class Exception>
  bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/, const Exception& error) {
    throw error;
  }

 private:
  struct Open {
    Json* node;                     // the object or array being filled
    const std::string* key = nullptr;  // objects: the member being parsed (the key in the map)
    Json* slot = nullptr;              // objects: that member's value
  };

  // Places a parsed value: the root, the next element of the open array, or the member whose
  // key came last. Returns where it lies (stable while it is open: an array's vector grows only
  // after its open element is closed, and map members never move).
  Json* place(Json&& value) {
    if (open_.empty()) {
      root_ = std::move(value);
      return &root_;
    }
    Open& top = open_.back();
    if (top.node->is_array()) {
      auto& elements = top.node->get_ref<Json::array_t&>();
      elements.push_back(std::move(value));
      return &elements.back();
    }
    *top.slot = std::move(value);
    return top.slot;
  }

  bool add(Json&& value) {
    place(std::move(value));
    return true;
  }

  bool open(Json::value_t type) {
    open_.push_back(Open{place(Json(type))});
    return true;
  }

  bool close() {
    open_.pop_back();
    return true;
  }

  // The JSON path of the value being parsed: "fluids[1].box.min".
  std::string path() const {
    std::string p;
    for (const Open& o : open_)
      p = o.node->is_array() ? element_path(p, o.node->size() - 1) : member_path(p, *o.key);
    return p;
  }

  const std::string* file_;
  Json root_;
  std::vector<Open> open_;
};

// "line 3, column 14" of the 0-based byte offset `pos` (clamped to the end of the text).
std::string line_and_column(std::string_view text, std::size_t pos) {
  pos = std::min(pos, text.size());
  const auto before = text.substr(0, pos);
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t line_start = before.rfind('\n');
  const std::size_t column = line_start == std::string_view::npos ? pos + 1 : pos - line_start;
  return fmt::format("line {}, column {}", line, column);
}

}  // namespace

Json parse_json(std::string_view text, const std::string& file) {
  try {
    SceneDocumentBuilder builder(file);
    Json::sax_parse(text.begin(), text.end(), &builder);
    return builder.take_document();
  } catch (const Json::parse_error& e) {
    // e.what() is "[json.exception.parse_error.101] parse error at line 4, column 0: <detail>".
    // nlohmann counts a newline as the start of the next line, so "tru\n" would be reported on
    // the line below the typo; recomputing from the byte offset names the line of the last read
    // character (e.byte is 1-based).
    const std::string message = e.what();
    const auto at = message.find(": ", message.find("parse error"));
    const std::string detail = at == std::string::npos ? message : message.substr(at + 2);
    fail(file, "", fmt::format("malformed JSON at {}: {}", line_and_column(text, e.byte > 0 ? e.byte - 1 : 0), detail));
  } catch (const Json::exception& e) {
    // out_of_range.406 "number overflow parsing '1e400'" has no offset: find the literal.
    std::string message = e.what();
    const auto bracket = message.find("] ");
    if (bracket != std::string::npos) message = message.substr(bracket + 2);
    const auto open = message.find('\'');
    const auto close = message.rfind('\'');
    const auto pos = open < close ? text.find(std::string_view(message).substr(open + 1, close - open - 1))
                                  : std::string_view::npos;
    fail(file, "",
         pos == std::string_view::npos ? fmt::format("malformed JSON: {}", message)
                                       : fmt::format("malformed JSON at {}: {}", line_and_column(text, pos), message));
  }
}

}  // namespace seiche::detail
