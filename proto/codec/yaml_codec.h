// YAML (and JSON, which is YAML) text -> any protobuf message, by reflection.
// Unlike protobuf's own JSON parser it names the field path and the line of
// every mistake, so a user sees "line 12: material.linear_elastic.poissons_ratio:
// expected a number, got the string 'high'".
#pragma once

#include <google/protobuf/message.h>

#include <filesystem>
#include <string>
#include <string_view>

namespace pba::codec {

struct ParseError {
  std::string file;     // set by ReadYamlFile
  int line = 0;         // 1-based; 0 when unknown
  std::string field;    // dotted path, e.g. "boundary_conditions[1].set"; empty for the whole text
  std::string message;  // what is wrong
  bool unreadable = false;  // the file could not be read at all (not the text's fault)
  // "scene.yaml:12: boundary_conditions[1].set: ..." with the parts that are known.
  std::string ToString() const;
};

// Field names are the proto names (snake_case); lowerCamelCase JSON names are
// accepted too. Enum values are matched by name, case-insensitively. Numbers
// must be plain YAML numbers (not quoted strings). A key that is not a field,
// a value of the wrong type, or two members of one oneof are errors. Returns
// false and fills `error` on failure; `message` is then unspecified.
bool ParseYaml(std::string_view text, google::protobuf::Message* message, ParseError* error);

// Reads a .yaml/.yml/.json file with ParseYaml; a missing or unreadable file
// is an error naming the path.
bool ReadYamlFile(const std::filesystem::path& path, google::protobuf::Message* message,
                  ParseError* error);

// Proto3 JSON with proto field names: indented for files and people, or on
// one line (for line protocols such as pba-solve's progress events).
std::string ToJson(const google::protobuf::Message& message);
std::string ToJsonLine(const google::protobuf::Message& message);

}  // namespace pba::codec
