#include "core/yaml_guard.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>
#include <vector>

namespace pba {
namespace {

// Counts nodes and depth; remembers the first problem and then ignores the
// rest of the stream (HandleNextDocument cannot be stopped from here
// without throwing through yaml-cpp).
class GuardHandler : public YAML::EventHandler {
 public:
  explicit GuardHandler(const YamlLimits& limits) : limits_(limits) {}

  // yaml-cpp numbers anchors afresh in each document.
  void OnDocumentStart(const YAML::Mark&) override { anchors_.clear(); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Node(mark); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const std::string name = anchor >= 1 && static_cast<size_t>(anchor) <= anchors_.size()
                                 ? anchors_[anchor - 1]
                                 : std::string("...");
    Fail(mark, "YAML aliases (*" + name +
                   ") are not accepted: an alias repeats its anchor's value wherever it is "
                   "used, and a small file of nested aliases expands to billions of values; "
                   "write the value out instead");
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string&) override {
    Node(mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Open(mark);
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Open(mark);
  }
  void OnMapEnd() override { --depth_; }
  void OnAnchor(const YAML::Mark&, const std::string& name) override { anchors_.push_back(name); }

  bool failed() const { return !message_.empty(); }
  const std::string& message() const { return message_; }
  int line() const { return line_; }

 private:
  void Node(const YAML::Mark& mark) {
    if (++nodes_ > limits_.max_nodes) {
      Fail(mark, "more than " + std::to_string(limits_.max_nodes) + " YAML values");
    }
  }
  void Open(const YAML::Mark& mark) {
    Node(mark);
    if (++depth_ > limits_.max_depth) {
      Fail(mark, "nested deeper than " + std::to_string(limits_.max_depth) + " levels");
    }
  }
  void Fail(const YAML::Mark& mark, const std::string& what) {
    if (failed()) return;
    line_ = mark.line >= 0 ? mark.line + 1 : 0;
    message_ = what;
  }

  const YamlLimits& limits_;
  std::vector<std::string> anchors_;  // by anchor id - 1
  size_t nodes_ = 0;
  int depth_ = 0;
  int line_ = 0;
  std::string message_;
};

}  // namespace

YamlProblem FindYamlProblem(std::string_view text, const YamlLimits& limits) {
  if (text.size() > limits.max_bytes) {
    return {0, "the text is " + std::to_string(text.size()) + " bytes; at most " +
                   std::to_string(limits.max_bytes) + " are accepted"};
  }
  std::istringstream stream{std::string(text)};
  GuardHandler handler(limits);
  try {
    YAML::Parser parser(stream);
    while (!handler.failed() && parser.HandleNextDocument(handler)) {
    }
  } catch (const YAML::Exception&) {
    // Malformed (or nested past yaml-cpp's own depth guard): the load that
    // follows reports it with its own message and line.
  }
  if (!handler.failed()) return {};
  return {handler.line(), handler.message()};
}

Status CheckYamlText(std::string_view text, const std::string& field, const YamlLimits& limits) {
  const YamlProblem problem = FindYamlProblem(text, limits);
  if (problem.message.empty()) return Status::Ok();
  const std::string where = problem.line > 0 ? "line " + std::to_string(problem.line) + ": " : "";
  return Status::InvalidArgument(field, where + problem.message);
}

Status ReadYamlFileText(const std::filesystem::path& path, const std::string& field,
                        std::string* text, const YamlLimits& limits) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot open " + path.string());
  // In pieces, one byte past the limit at most: the size on disk may be
  // unknown (a pipe) or change while it is read.
  std::string read;
  char buffer[65536];
  while (read.size() <= limits.max_bytes && in.read(buffer, sizeof buffer).gcount() > 0) {
    read.append(buffer, static_cast<size_t>(in.gcount()));
  }
  if (in.bad()) return Status::Io("cannot read " + path.string());
  if (read.size() > limits.max_bytes) {
    return Status::InvalidArgument(field, "the file holds more than " +
                                              std::to_string(limits.max_bytes) +
                                              " bytes, the most accepted");
  }
  PBA_RETURN_IF_ERROR(CheckYamlText(read, field, limits));
  *text = std::move(read);
  return Status::Ok();
}

}  // namespace pba
