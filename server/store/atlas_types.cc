#include "store/atlas_types.h"

#include <cctype>
#include <cstdio>

namespace pba {
namespace {

// How a refused character is shown: printable ones quoted, the rest as \xNN
// so that a NUL or an escape sequence cannot garble the message.
std::string Describe(char c) {
  const auto byte = static_cast<unsigned char>(c);
  if (byte >= 0x20 && byte < 0x7f) return std::string("'") + c + "'";
  char buffer[8];
  std::snprintf(buffer, sizeof(buffer), "\\x%02x", byte);
  return buffer;
}

bool IsNameCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == ' ' ||
         c == '_' || c == '-' || c == '.' || c == '(' || c == ')' || c == ':';
}

// A validating JSON reader (RFC 8259) that builds nothing: the store keeps the
// text verbatim and only needs to know it will parse later.
class JsonChecker {
 public:
  explicit JsonChecker(std::string_view text) : text_(text) {}

  // Empty on success, else what is wrong and where.
  std::string CheckObjectDocument() {
    SkipSpace();
    if (Peek() != '{') return Error("the top level must be a JSON object");
    if (!Value(0)) return error_;
    SkipSpace();
    if (pos_ != text_.size()) return Error("unexpected text after the object");
    return "";
  }

 private:
  static constexpr int kMaxDepth = 64;

  char Peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }
  bool Consume() {
    ++pos_;
    return true;
  }
  void SkipSpace() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t' ||
                                   text_[pos_] == '\n' || text_[pos_] == '\r')) {
      ++pos_;
    }
  }
  std::string Error(const std::string& what) {
    error_ = what + " at byte " + std::to_string(pos_);
    return error_;
  }
  bool Fail(const std::string& what) {
    Error(what);
    return false;
  }
  bool Literal(std::string_view word) {
    if (text_.substr(pos_, word.size()) != word) return Fail("invalid literal");
    pos_ += word.size();
    return true;
  }
  bool Digits() {
    const size_t start = pos_;
    while (Peek() >= '0' && Peek() <= '9') ++pos_;
    return pos_ > start;
  }
  bool Number() {
    if (Peek() == '-') ++pos_;
    if (Peek() == '0') {
      ++pos_;
    } else if (!Digits()) {
      return Fail("invalid number");
    }
    if (Peek() == '.') {
      ++pos_;
      if (!Digits()) return Fail("invalid number");
    }
    if (Peek() == 'e' || Peek() == 'E') {
      ++pos_;
      if (Peek() == '+' || Peek() == '-') ++pos_;
      if (!Digits()) return Fail("invalid number");
    }
    return true;
  }
  bool String() {
    ++pos_;  // the opening quote
    while (pos_ < text_.size()) {
      const char c = text_[pos_++];
      if (c == '"') return true;
      if (static_cast<unsigned char>(c) < 0x20) return Fail("control character in a string");
      if (c != '\\') continue;
      const char escape = Peek();
      ++pos_;
      if (escape == 'u') {
        for (int i = 0; i < 4; ++i, ++pos_) {
          if (!std::isxdigit(static_cast<unsigned char>(Peek()))) return Fail("invalid \\u escape");
        }
      } else if (std::string_view("\"\\/bfnrt").find(escape) == std::string_view::npos ||
                 escape == '\0') {
        return Fail("invalid escape");
      }
    }
    return Fail("unterminated string");
  }
  bool Value(int depth) {
    if (depth > kMaxDepth) return Fail("nested deeper than " + std::to_string(kMaxDepth));
    SkipSpace();
    switch (Peek()) {
      case '{': {
        ++pos_;
        SkipSpace();
        if (Peek() == '}') return Consume();
        while (true) {
          SkipSpace();
          if (Peek() != '"') return Fail("expected a member name");
          if (!String()) return false;
          SkipSpace();
          if (Peek() != ':') return Fail("expected ':'");
          ++pos_;
          if (!Value(depth + 1)) return false;
          SkipSpace();
          if (Peek() == '}') return Consume();
          if (Peek() != ',') return Fail("expected ',' or '}'");
          ++pos_;
        }
      }
      case '[': {
        ++pos_;
        SkipSpace();
        if (Peek() == ']') return Consume();
        while (true) {
          if (!Value(depth + 1)) return false;
          SkipSpace();
          if (Peek() == ']') return Consume();
          if (Peek() != ',') return Fail("expected ',' or ']'");
          ++pos_;
        }
      }
      case '"':
        return String();
      case 't':
        return Literal("true");
      case 'f':
        return Literal("false");
      case 'n':
        return Literal("null");
      default:
        if (Peek() == '-' || (Peek() >= '0' && Peek() <= '9')) return Number();
        return Fail("expected a value");
    }
  }

  std::string_view text_;
  size_t pos_ = 0;
  std::string error_;
};

}  // namespace

const char* RoleName(Role role) {
  switch (role) {
    case Role::kViewer:
      return "viewer";
    case Role::kEditor:
      return "editor";
    case Role::kAdmin:
      return "admin";
  }
  return "viewer";
}

bool ParseRole(std::string_view name, Role* role) {
  for (Role r : {Role::kViewer, Role::kEditor, Role::kAdmin}) {
    if (name == RoleName(r)) {
      *role = r;
      return true;
    }
  }
  return false;
}

Status CheckName(std::string_view field, std::string_view name) {
  const std::string f(field);
  if (name.empty()) return Status::InvalidArgument(f, "must not be empty");
  if (name.size() > kMaxNameLength) {
    return Status::InvalidArgument(f, "is " + std::to_string(name.size()) +
                                          " characters long; the limit is " +
                                          std::to_string(kMaxNameLength));
  }
  for (size_t i = 0; i < name.size(); ++i) {
    if (!IsNameCharacter(name[i])) {
      return Status::InvalidArgument(
          f, "character " + Describe(name[i]) + " at position " + std::to_string(i + 1) +
                 " is not allowed; names use letters, digits, space and _ - . ( ) :");
    }
  }
  if (name.front() == ' ' || name.back() == ' ') {
    return Status::InvalidArgument(f, "must not start or end with a space");
  }
  if (name == "." || name == "..") return Status::InvalidArgument(f, "must not be . or ..");
  return Status::Ok();
}

Status CheckGroupPath(std::string_view field, std::string_view path) {
  if (path.empty()) return Status::Ok();
  if (path.size() > kMaxGroupPathLength) {
    return Status::InvalidArgument(
        std::string(field),
        "is longer than " + std::to_string(kMaxGroupPathLength) + " characters");
  }
  size_t start = 0;
  while (true) {
    const size_t slash = path.find('/', start);
    const std::string_view part = path.substr(start, slash - start);
    if (part.empty()) {
      return Status::InvalidArgument(std::string(field),
                                     "'/' separates group names and cannot lead, trail or repeat");
    }
    PBA_RETURN_IF_ERROR(CheckName(field, part));
    if (slash == std::string_view::npos) return Status::Ok();
    start = slash + 1;
  }
}

Status CheckColour(std::string_view field, const Colour& colour) {
  const std::pair<const char*, int> components[] = {
      {"r", colour.r}, {"g", colour.g}, {"b", colour.b}};
  for (const auto& [name, value] : components) {
    if (value < 0 || value > 255) {
      return Status::InvalidArgument(std::string(field) + "." + name,
                                     std::to_string(value) + " is outside 0..255");
    }
  }
  return Status::Ok();
}

Status CheckMaterialJson(std::string_view field, std::string_view json) {
  if (json.size() > kMaxMaterialJsonBytes) {
    return Status::InvalidArgument(
        std::string(field), "is larger than " + std::to_string(kMaxMaterialJsonBytes) + " bytes");
  }
  const std::string error = JsonChecker(json).CheckObjectDocument();
  if (!error.empty()) {
    return Status::InvalidArgument(std::string(field), "not a JSON object: " + error);
  }
  return Status::Ok();
}

Status CheckMessage(std::string_view field, std::string_view message) {
  if (message.size() > kMaxMessageBytes) {
    return Status::InvalidArgument(std::string(field),
                                   "is longer than " + std::to_string(kMaxMessageBytes) + " bytes");
  }
  for (size_t i = 0; i < message.size(); ++i) {
    const auto byte = static_cast<unsigned char>(message[i]);
    if ((byte < 0x20 && message[i] != '\n' && message[i] != '\t') || byte == 0x7f) {
      return Status::InvalidArgument(
          std::string(field),
          "control character " + Describe(message[i]) + " at position " + std::to_string(i + 1));
    }
  }
  return Status::Ok();
}

Status CheckMetadata(const StructureMetadata& metadata) {
  PBA_RETURN_IF_ERROR(CheckColour("colour", metadata.colour));
  PBA_RETURN_IF_ERROR(CheckGroupPath("group_path", metadata.group_path));
  return CheckMaterialJson("material_json", metadata.material_json);
}

}  // namespace pba
