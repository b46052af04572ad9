#include "codec/yaml_codec.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/util/json_util.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/yaml_guard.h"

namespace pba::codec {
namespace {

// A scene is a few kilobytes; these bounds leave room for generated ones
// (studies, batches) and keep a hostile one from costing gigabytes.
const YamlLimits kSceneYamlLimits{size_t{16} << 20, 1'000'000, 64};

using google::protobuf::Descriptor;
using google::protobuf::EnumDescriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::OneofDescriptor;
using google::protobuf::Reflection;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += ", ";
    out += item;
  }
  return out;
}

std::string KindName(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return node.Tag() == "!" ? "the string '" + node.Scalar() + "'" : "'" + node.Scalar() + "'";
    default:
      return "an undefined value";
  }
}

class Parser {
 public:
  explicit Parser(ParseError* error) : error_(error) {}

  bool ParseMessage(const YAML::Node& node, Message* message, const std::string& path) {
    if (node.IsNull()) return true;  // "key:" with nothing after it: an empty message
    if (!node.IsMap())
      return Fail(node, path, "expected a mapping of fields, got " + KindName(node));
    const Descriptor* descriptor = message->GetDescriptor();
    const Reflection* reflection = message->GetReflection();
    std::vector<const OneofDescriptor*> seen_oneofs;
    std::vector<std::string> seen_oneof_fields;
    std::vector<const FieldDescriptor*> seen_fields;
    for (const auto& entry : node) {
      const YAML::Node& key = entry.first;
      if (!key.IsScalar()) return Fail(key, path, "a field name must be a plain word");
      const std::string name = key.Scalar();
      const FieldDescriptor* field = descriptor->FindFieldByName(name);
      if (field == nullptr) field = descriptor->FindFieldByCamelcaseName(name);
      const std::string field_path = path.empty() ? name : path + "." + name;
      if (field == nullptr) {
        std::vector<std::string> names;
        for (int i = 0; i < descriptor->field_count(); ++i)
          names.push_back(descriptor->field(i)->name());
        return Fail(key, field_path,
                    "unknown field '" + name + "' (expected one of: " + Join(names) + ")");
      }
      if (std::find(seen_fields.begin(), seen_fields.end(), field) != seen_fields.end()) {
        return Fail(key, field_path, "'" + name + "' is given twice");
      }
      seen_fields.push_back(field);
      if (const OneofDescriptor* oneof = field->real_containing_oneof()) {
        auto it = std::find(seen_oneofs.begin(), seen_oneofs.end(), oneof);
        if (it != seen_oneofs.end()) {
          const std::string& other = seen_oneof_fields[it - seen_oneofs.begin()];
          return Fail(key, field_path,
                      "only one of the " + oneof->name() + " choices may be given, but both '" +
                          other + "' and '" + name + "' are");
        }
        seen_oneofs.push_back(oneof);
        seen_oneof_fields.push_back(name);
      }
      if (!ParseField(entry.second, message, reflection, field, field_path)) return false;
    }
    return true;
  }

 private:
  bool ParseField(const YAML::Node& node, Message* message, const Reflection* reflection,
                  const FieldDescriptor* field, const std::string& path) {
    if (field->is_map()) return Fail(node, path, "map fields cannot be read from YAML");
    if (field->is_repeated()) {
      if (node.IsNull()) return true;
      if (!node.IsSequence()) return Fail(node, path, "expected a list, got " + KindName(node));
      for (std::size_t i = 0; i < node.size(); ++i) {
        if (!ParseValue(node[i], message, reflection, field, path + "[" + std::to_string(i) + "]"))
          return false;
      }
      return true;
    }
    return ParseValue(node, message, reflection, field, path);
  }

  bool ParseValue(const YAML::Node& node, Message* message, const Reflection* reflection,
                  const FieldDescriptor* field, const std::string& path) {
    const bool repeated = field->is_repeated();
    if (field->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) {
      Message* child = repeated ? reflection->AddMessage(message, field)
                                : reflection->MutableMessage(message, field);
      return ParseMessage(node, child, path);
    }
    if (!node.IsScalar()) {
      return Fail(node, path, "expected " + ScalarKind(field) + ", got " + KindName(node));
    }
    const std::string& text = node.Scalar();
    const bool quoted = node.Tag() == "!";
    switch (field->cpp_type()) {
      case FieldDescriptor::CPPTYPE_DOUBLE:
      case FieldDescriptor::CPPTYPE_FLOAT: {
        double value = 0;
        if (quoted || !ParseDouble(text, &value)) return WrongType(node, path, field);
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_FLOAT) {
          repeated ? reflection->AddFloat(message, field, static_cast<float>(value))
                   : reflection->SetFloat(message, field, static_cast<float>(value));
        } else {
          repeated ? reflection->AddDouble(message, field, value)
                   : reflection->SetDouble(message, field, value);
        }
        return true;
      }
      case FieldDescriptor::CPPTYPE_INT32:
      case FieldDescriptor::CPPTYPE_INT64:
      case FieldDescriptor::CPPTYPE_UINT32:
      case FieldDescriptor::CPPTYPE_UINT64:
        return ParseInteger(node, text, quoted, message, reflection, field, path);
      case FieldDescriptor::CPPTYPE_BOOL: {
        const std::string lower = Lower(text);
        bool value;
        if (quoted) return WrongType(node, path, field);
        if (lower == "true" || lower == "yes" || lower == "on") {
          value = true;
        } else if (lower == "false" || lower == "no" || lower == "off") {
          value = false;
        } else {
          return WrongType(node, path, field);
        }
        repeated ? reflection->AddBool(message, field, value)
                 : reflection->SetBool(message, field, value);
        return true;
      }
      case FieldDescriptor::CPPTYPE_STRING:
        repeated ? reflection->AddString(message, field, text)
                 : reflection->SetString(message, field, text);
        return true;
      case FieldDescriptor::CPPTYPE_ENUM:
        return ParseEnum(node, text, message, reflection, field, path);
      default:
        return Fail(node, path, "unsupported field type");
    }
  }

  bool ParseInteger(const YAML::Node& node, const std::string& text, bool quoted, Message* message,
                    const Reflection* reflection, const FieldDescriptor* field,
                    const std::string& path) {
    if (quoted) return WrongType(node, path, field);
    long long value = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size()) return WrongType(node, path, field);
    const bool repeated = field->is_repeated();
    auto out_of_range = [&] {
      return Fail(node, path, "the integer " + text + " is out of range");
    };
    switch (field->cpp_type()) {
      case FieldDescriptor::CPPTYPE_INT32:
        if (value < std::numeric_limits<int32_t>::min() ||
            value > std::numeric_limits<int32_t>::max())
          return out_of_range();
        repeated ? reflection->AddInt32(message, field, static_cast<int32_t>(value))
                 : reflection->SetInt32(message, field, static_cast<int32_t>(value));
        return true;
      case FieldDescriptor::CPPTYPE_INT64:
        repeated ? reflection->AddInt64(message, field, value)
                 : reflection->SetInt64(message, field, value);
        return true;
      case FieldDescriptor::CPPTYPE_UINT32:
        if (value < 0 || value > std::numeric_limits<uint32_t>::max()) return out_of_range();
        repeated ? reflection->AddUInt32(message, field, static_cast<uint32_t>(value))
                 : reflection->SetUInt32(message, field, static_cast<uint32_t>(value));
        return true;
      default:
        if (value < 0) return out_of_range();
        repeated ? reflection->AddUInt64(message, field, static_cast<uint64_t>(value))
                 : reflection->SetUInt64(message, field, static_cast<uint64_t>(value));
        return true;
    }
  }

  bool ParseEnum(const YAML::Node& node, const std::string& text, Message* message,
                 const Reflection* reflection, const FieldDescriptor* field,
                 const std::string& path) {
    const EnumDescriptor* type = field->enum_type();
    std::vector<std::string> names;
    for (int i = 0; i < type->value_count(); ++i) {
      const auto* value = type->value(i);
      if (value->number() == 0) continue;  // *_UNSPECIFIED: the default, not a choice
      names.push_back(value->name());
      if (Lower(value->name()) == Lower(text)) {
        field->is_repeated() ? reflection->AddEnumValue(message, field, value->number())
                             : reflection->SetEnumValue(message, field, value->number());
        return true;
      }
    }
    return Fail(node, path, "unknown value '" + text + "' (expected one of: " + Join(names) + ")");
  }

  static bool ParseDouble(const std::string& text, double* value) {
    if (text.empty()) return false;
    const std::string lower = Lower(text);
    if (lower == ".inf" || lower == "+.inf") {
      *value = std::numeric_limits<double>::infinity();
      return true;
    }
    if (lower == "-.inf") {
      *value = -std::numeric_limits<double>::infinity();
      return true;
    }
    if (lower == ".nan") {
      *value = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
    const char* begin = text.data();
    if (*begin == '+') ++begin;
    auto [end, ec] = std::from_chars(begin, text.data() + text.size(), *value);
    return ec == std::errc() && end == text.data() + text.size();
  }

  static std::string ScalarKind(const FieldDescriptor* field) {
    switch (field->cpp_type()) {
      case FieldDescriptor::CPPTYPE_DOUBLE:
      case FieldDescriptor::CPPTYPE_FLOAT:
        return "a number";
      case FieldDescriptor::CPPTYPE_INT32:
      case FieldDescriptor::CPPTYPE_INT64:
      case FieldDescriptor::CPPTYPE_UINT32:
      case FieldDescriptor::CPPTYPE_UINT64:
        return "an integer";
      case FieldDescriptor::CPPTYPE_BOOL:
        return "true or false";
      case FieldDescriptor::CPPTYPE_ENUM:
        return "one of the names of " + field->enum_type()->name();
      default:
        return "a text value";
    }
  }

  bool WrongType(const YAML::Node& node, const std::string& path, const FieldDescriptor* field) {
    return Fail(node, path, "expected " + ScalarKind(field) + ", got " + KindName(node));
  }

  bool Fail(const YAML::Node& node, const std::string& path, const std::string& message) {
    error_->field = path;
    error_->line = node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
    error_->message = message;
    return false;
  }

  ParseError* error_;
};

}  // namespace

std::string ParseError::ToString() const {
  std::string out = file;
  if (line > 0) out += (out.empty() ? "line " : ":") + std::to_string(line);
  if (!out.empty()) out += ": ";
  if (!field.empty()) out += field + ": ";
  return out + message;
}

bool ParseYaml(std::string_view text, Message* message, ParseError* error) {
  // Aliases and oversized texts are refused before loading: walking a tree
  // of nested aliases visits each reference again (yaml_guard.h), and a
  // scene of a few hundred bytes ran the client out of memory.
  const YamlProblem problem = FindYamlProblem(text, kSceneYamlLimits);
  if (!problem.message.empty()) {
    error->field.clear();
    error->line = problem.line;
    error->message = problem.message;
    return false;
  }
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    error->field.clear();
    error->line = e.mark.line >= 0 ? e.mark.line + 1 : 0;
    error->message = "not valid YAML: " + e.msg;
    return false;
  }
  if (!root.IsDefined() || root.IsNull()) {
    error->field.clear();
    error->message = "the document is empty";
    return false;
  }
  message->Clear();
  return Parser(error).ParseMessage(root, message, "");
}

bool ReadYamlFile(const std::filesystem::path& path, Message* message, ParseError* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error->field.clear();
    error->unreadable = true;
    error->message = "cannot read " + path.string() + ": no such file or not readable";
    return false;
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (!ParseYaml(text.str(), message, error)) {
    error->file = path.string();
    return false;
  }
  return true;
}

namespace {

std::string PrintJson(const Message& message, bool indented) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = indented;
  options.preserve_proto_field_names = true;
  std::string out;
  // Printing a well-formed message cannot fail.
  (void)google::protobuf::util::MessageToJsonString(message, &out, options);
  return out;
}

}  // namespace

std::string ToJson(const Message& message) { return PrintJson(message, true); }

std::string ToJsonLine(const Message& message) { return PrintJson(message, false); }

}  // namespace pba::codec
