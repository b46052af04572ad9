#include "web/web_server.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <openssl/crypto.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "core/format.h"
#include "core/sha256.h"
#include "service/handler.h"
#include "store/random_hex.h"
#include "web/web_gateway.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr char kCookie[] = "pba_token";
constexpr char kCsrfHeader[] = "X-PBA-CSRF";
// Tokens are the store's (random hex); anything else is not one.
constexpr std::size_t kMaxToken = 256;
// How long one API call may take on the gRPC side.
constexpr std::chrono::seconds kCallDeadline{60};
// The application's files at most (each, and in all): they are read once.
constexpr std::uintmax_t kMaxAppFile = std::uintmax_t{8} << 20;

constexpr char kThreeInPackage[] = "\"../../../build/three.module.js\"";
constexpr char kThreeServed[] = "\"/vendor/three.module.js\"";

// Files of Debian's packages the page imports, by the name it asks for.
const std::map<std::string, std::string>& VendorFiles() {
  static const std::map<std::string, std::string> files = {
      {"three.module.js", "three/build/three.module.js"},
      {"OrbitControls.js", "three/examples/jsm/controls/OrbitControls.js"},
      {"GLTFLoader.js", "three/examples/jsm/loaders/GLTFLoader.js"},
      {"chart.min.js", "chart.js/chart.min.js"},
  };
  return files;
}

std::string ContentType(const fs::path& name) {
  const std::string ext = name.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  return "application/octet-stream";
}

bool ReadWhole(const fs::path& path, std::string* text) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size > kMaxAppFile) return false;
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  *text = out.str();
  return static_cast<bool>(in) || in.eof();
}

bool IsTokenText(const std::string& token) {
  if (token.empty() || token.size() > kMaxToken) return false;
  for (const char c : token) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') {
      return false;
    }
  }
  return true;
}

// The token of the request's session cookie ("" without a well-formed one).
std::string CookieToken(const httplib::Request& request) {
  const std::string header = request.get_header_value("Cookie");
  const std::string key = std::string(kCookie) + "=";
  std::size_t at = 0;
  while (at < header.size()) {
    while (at < header.size() && (header[at] == ' ' || header[at] == ';')) ++at;
    const std::size_t end = std::min(header.find(';', at), header.size());
    if (header.compare(at, key.size(), key) == 0) {
      const std::string value = header.substr(at + key.size(), end - at - key.size());
      return IsTokenText(value) ? value : "";
    }
    at = end;
  }
  return "";
}

int HttpStatusOf(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return 200;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE:
      return 400;
    case grpc::StatusCode::UNAUTHENTICATED:
      return 401;
    case grpc::StatusCode::PERMISSION_DENIED:
      return 403;
    case grpc::StatusCode::NOT_FOUND:
      return 404;
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::ABORTED:
    case grpc::StatusCode::FAILED_PRECONDITION:
      return 409;
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return 429;
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return 503;
    default:
      return 500;
  }
}

void SendError(httplib::Response& response, grpc::StatusCode code, const std::string& message) {
  response.status = HttpStatusOf(code);
  response.set_header("Cache-Control", "no-store");
  response.set_content(
      "{\"code\":" + JsonQuoted(GrpcCodeName(code)) + ",\"message\":" + JsonQuoted(message) + "}",
      "application/json");
}

}  // namespace

struct WebServer::State {
  explicit State(std::shared_ptr<grpc::Channel> channel) : gateway(std::move(channel)) {}

  WebGateway gateway;
  bool tls = false;
  std::string secret;                        // of this start: CSRF tokens die with it
  std::map<std::string, std::string> files;  // "/..." -> content, read at start
  std::map<std::string, std::string> types;  // "/..." -> its Content-Type

  std::string Csrf(const std::string& token) const { return Sha256Hex(secret + ":" + token); }

  // A request from a page of another site: its Origin (sent with every
  // POST and DELETE by browsers) is not this server's own.
  static bool CrossSite(const httplib::Request& request, bool tls) {
    if (request.get_header_value("Sec-Fetch-Site") == "cross-site") return true;
    if (!request.has_header("Origin")) return false;
    const std::string own = (tls ? "https://" : "http://") + request.get_header_value("Host");
    return request.get_header_value("Origin") != own;
  }

  // Whether the request may change or read anything through the API: a
  // session, from this site, with the session's CSRF token. Answers the
  // error itself when not.
  bool Admit(const httplib::Request& request, httplib::Response& response, std::string* token) {
    *token = CookieToken(request);
    if (token->empty()) {
      SendError(response, grpc::StatusCode::UNAUTHENTICATED, "not signed in");
      return false;
    }
    if (CrossSite(request, tls)) {
      SendError(response, grpc::StatusCode::PERMISSION_DENIED, "a request from another site");
      return false;
    }
    const std::string sent = request.get_header_value(kCsrfHeader);
    const std::string expected = Csrf(*token);
    if (sent.size() != expected.size() ||
        CRYPTO_memcmp(sent.data(), expected.data(), expected.size()) != 0) {
      SendError(response, grpc::StatusCode::PERMISSION_DENIED,
                std::string("the request lacks this session's ") + kCsrfHeader + " header");
      return false;
    }
    return true;
  }

  // The gRPC call `name` as `token`'s user; true when it succeeded.
  bool Call(const std::string& name, const std::string& token, const std::string& body,
            httplib::Response& response, std::string* json) {
    const GatewayCall* call = gateway.Find(name);
    if (call == nullptr) {
      SendError(response, grpc::StatusCode::NOT_FOUND, "no API call " + name);
      return false;
    }
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
    const grpc::Status status = (*call)(&context, body, json);
    if (!status.ok()) {
      SendError(response, status.error_code(), status.error_message());
      return false;
    }
    return true;
  }

  // The session's answer: {"user": ..., "csrf": ...}.
  void SendSession(httplib::Response& response, const std::string& token,
                   const std::string& user_json) {
    response.set_header("Cache-Control", "no-store");
    response.set_content("{\"user\":" + user_json + ",\"csrf\":" + JsonQuoted(Csrf(token)) + "}",
                         "application/json");
  }

  Status LoadFiles(const WebOptions& options) {
    const fs::path index = options.app_dir / "index.html";
    std::error_code ec;
    if (!fs::is_regular_file(index, ec)) {
      return Status::FailedPrecondition("the web application is not installed: no " +
                                        index.string());
    }
    static const std::regex kName("[A-Za-z0-9][A-Za-z0-9._-]*");
    for (const fs::directory_entry& entry : fs::directory_iterator(options.app_dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (!entry.is_regular_file() || !std::regex_match(name, kName)) continue;
      std::string text;
      if (!ReadWhole(entry.path(), &text)) {
        return Status::Io("cannot read " + entry.path().string() + " (at most 8 MiB)");
      }
      const std::string route = name == "index.html" ? "/" : "/app/" + name;
      files[route] = std::move(text);
      types[route] = ContentType(name);
    }
    for (const auto& [name, relative] : VendorFiles()) {
      const fs::path path = options.vendor_dir / relative;
      std::string text;
      if (!ReadWhole(path, &text)) {
        return Status::FailedPrecondition(
            "--http needs Debian's libjs-three and libjs-chart.js: cannot read " + path.string());
      }
      // three.js's examples import the library by its place in the
      // package; here it is /vendor/three.module.js (the page's content
      // security policy allows no inline import map).
      for (std::size_t at; (at = text.find(kThreeInPackage)) != std::string::npos;) {
        text.replace(at, std::strlen(kThreeInPackage), kThreeServed);
      }
      files["/vendor/" + name] = std::move(text);
      types["/vendor/" + name] = ContentType(name);
    }
    return Status::Ok();
  }
};

Status WebServer::Start(const WebOptions& options, std::shared_ptr<grpc::Channel> channel,
                        std::unique_ptr<WebServer>* out) {
  std::unique_ptr<WebServer> web(new WebServer());
  web->state_ = std::make_unique<State>(std::move(channel));
  State& state = *web->state_;
  PBA_RETURN_IF_ERROR(state.LoadFiles(options));
  PBA_RETURN_IF_ERROR(RandomHex(32, &state.secret));
  state.tls = !options.tls_cert.empty();
  if (state.tls) {
    auto ssl =
        std::make_unique<httplib::SSLServer>(options.tls_cert.c_str(), options.tls_key.c_str());
    if (!ssl->is_valid()) {
      return Status::InvalidArgument("tls_cert", "the certificate or key cannot be used for HTTPS");
    }
    web->http_ = std::move(ssl);
  } else {
    web->http_ = std::make_unique<httplib::Server>();
  }
  httplib::Server& http = *web->http_;
  const int threads = std::max(1, options.threads);
  http.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  http.set_payload_max_length(kWebMaxBody);
  http.set_read_timeout(30, 0);
  http.set_write_timeout(30, 0);
  http.set_keep_alive_max_count(100);
  http.set_default_headers({
      {"X-Content-Type-Options", "nosniff"},
      {"X-Frame-Options", "DENY"},
      {"Referrer-Policy", "no-referrer"},
      {"Content-Security-Policy",
       "default-src 'self'; img-src 'self' data: blob:; style-src 'self'; "
       "connect-src 'self'; frame-ancestors 'none'"},
  });

  http.Get(R"(/|/app/[A-Za-z0-9._-]+|/vendor/[A-Za-z0-9._-]+)",
           [&state](const httplib::Request& request, httplib::Response& response) {
             const auto it = state.files.find(request.path);
             if (it == state.files.end()) {
               response.status = 404;
               response.set_content("not found\n", "text/plain");
               return;
             }
             response.set_content(it->second, state.types.at(request.path).c_str());
           });

  http.Get("/api/session", [&state](const httplib::Request& request, httplib::Response& response) {
    const std::string token = CookieToken(request);
    if (token.empty()) {
      SendError(response, grpc::StatusCode::UNAUTHENTICATED, "not signed in");
      return;
    }
    std::string user;
    if (state.Call("AtlasService/WhoAmI", token, "{}", response, &user)) {
      state.SendSession(response, token, user);
    }
  });
  http.Post("/api/session", [&state](const httplib::Request& request, httplib::Response& response) {
    if (State::CrossSite(request, state.tls)) {
      SendError(response, grpc::StatusCode::PERMISSION_DENIED, "a request from another site");
      return;
    }
    google::protobuf::Struct body;
    std::string token;
    if (google::protobuf::util::JsonStringToMessage(request.body, &body).ok() &&
        body.fields().count("token") == 1) {
      token = body.fields().at("token").string_value();
    }
    if (!IsTokenText(token)) {
      SendError(response, grpc::StatusCode::INVALID_ARGUMENT,
                "expected {\"token\": \"...\"}, the access token `pba login` takes");
      return;
    }
    std::string user;
    if (!state.Call("AtlasService/WhoAmI", token, "{}", response, &user)) return;
    response.set_header("Set-Cookie", std::string(kCookie) + "=" + token +
                                          "; Path=/; HttpOnly; SameSite=Strict" +
                                          (state.tls ? "; Secure" : ""));
    state.SendSession(response, token, user);
  });
  http.Delete(
      "/api/session", [&state](const httplib::Request& request, httplib::Response& response) {
        if (State::CrossSite(request, state.tls)) {
          SendError(response, grpc::StatusCode::PERMISSION_DENIED, "a request from another site");
          return;
        }
        response.set_header("Set-Cookie", std::string(kCookie) +
                                              "=; Path=/; HttpOnly; SameSite=Strict; Max-Age=0" +
                                              (state.tls ? "; Secure" : ""));
        response.set_content("{}", "application/json");
      });

  http.Post(R"(/api/v1/([A-Za-z]+)/([A-Za-z]+))",
            [&state](const httplib::Request& request, httplib::Response& response) {
              std::string token;
              if (!state.Admit(request, response, &token)) return;
              std::string json;
              const std::string name = request.matches[1].str() + "/" + request.matches[2].str();
              if (state.Call(name, token, request.body, response, &json)) {
                response.set_header("Cache-Control", "no-store");
                response.set_content(json, "application/json");
              }
            });

  const std::size_t colon = options.listen.rfind(':');
  if (colon == std::string::npos) {
    return Status::InvalidArgument("http", "expected HOST:PORT, got " + options.listen);
  }
  const std::string host = options.listen.substr(0, colon);
  int port = 0;
  try {
    port = std::stoi(options.listen.substr(colon + 1));
  } catch (const std::exception&) {
    port = -1;
  }
  if (port < 0 || port > 65535) {
    return Status::InvalidArgument("http", "expected HOST:PORT, got " + options.listen);
  }
  if (port == 0) {
    port = http.bind_to_any_port(host.c_str());
  } else if (!http.bind_to_port(host.c_str(), port)) {
    port = -1;
  }
  if (port <= 0) return Status::Io("cannot listen on " + options.listen + " for HTTP");
  web->address_ = host + ":" + std::to_string(port);
  httplib::Server* serving = web->http_.get();
  web->thread_ = std::thread([serving] { serving->listen_after_bind(); });
  *out = std::move(web);
  return Status::Ok();
}

WebServer::~WebServer() { Stop(); }

void WebServer::Stop() {
  if (http_ != nullptr) http_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace pba
