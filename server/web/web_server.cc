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
#include <mutex>
#include <regex>
#include <set>
#include <sstream>

#include "core/format.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"
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
// Server-sent event streams open at once, and how long each lasts before
// the browser opens it again (EventSource does that by itself): a page
// that went away holds its thread at most that long.
constexpr int kMaxEventStreams = 16;
constexpr std::chrono::seconds kEventStreamLife{60};
// The most of each of the application's files: they are read once, at start.
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
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".csv") return "text/csv; charset=utf-8";
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

  // The calls of open event streams, cancelled by Stop.
  std::mutex streams_mutex;
  std::set<grpc::ClientContext*> streams;
  bool stopping = false;

  // Registers a stream's call; false when there are too many or the server
  // is stopping.
  bool OpenStream(grpc::ClientContext* context) {
    std::lock_guard lock(streams_mutex);
    if (stopping || static_cast<int>(streams.size()) >= kMaxEventStreams) return false;
    streams.insert(context);
    return true;
  }
  void CloseStream(grpc::ClientContext* context) {
    std::lock_guard lock(streams_mutex);
    streams.erase(context);
  }
  void CancelStreams() {
    std::lock_guard lock(streams_mutex);
    stopping = true;
    for (grpc::ClientContext* context : streams) context->TryCancel();
  }

  // A request from a page of another site: its Origin (sent with every
  // POST and DELETE by browsers) is not this server's own.
  static bool CrossSite(const httplib::Request& request, bool tls) {
    if (request.get_header_value("Sec-Fetch-Site") == "cross-site") return true;
    if (!request.has_header("Origin")) return false;
    const std::string own = (tls ? "https://" : "http://") + request.get_header_value("Host");
    return request.get_header_value("Origin") != own;
  }

  // The session's token of a request from this site; false (the error
  // answered) without a session or from another site.
  bool SessionOf(const httplib::Request& request, httplib::Response& response,
                 std::string* token) const {
    *token = CookieToken(request);
    if (token->empty()) {
      SendError(response, grpc::StatusCode::UNAUTHENTICATED, "not signed in");
      return false;
    }
    if (CrossSite(request, tls)) {
      SendError(response, grpc::StatusCode::PERMISSION_DENIED, "a request from another site");
      return false;
    }
    return true;
  }

  // Whether the request may change or read anything through the API: a
  // session, from this site, with the session's CSRF token. Answers the
  // error itself when not.
  bool Admit(const httplib::Request& request, httplib::Response& response, std::string* token) {
    if (!SessionOf(request, response, token)) return false;
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

  // A project's changes as server-sent events: each AtlasEvent of the
  // gRPC Watch as `data: <its JSON>`, the first one READY.
  void Events(const httplib::Request& request, httplib::Response& response) {
    std::string token;
    if (!SessionOf(request, response, &token)) return;
    struct Stream {
      State* state = nullptr;
      grpc::ClientContext context;
      std::unique_ptr<grpc::ClientReader<v1::AtlasEvent>> reader;
      v1::AtlasEvent event;
      bool pending = false;
    };
    auto stream = std::make_shared<Stream>();
    stream->state = this;
    stream->context.AddMetadata("authorization", "Bearer " + token);
    stream->context.set_deadline(std::chrono::system_clock::now() + kEventStreamLife);
    if (!OpenStream(&stream->context)) {
      SendError(response, grpc::StatusCode::UNAVAILABLE,
                "too many event streams open; the page polls instead");
      return;
    }
    v1::WatchRequest watch;
    watch.set_project(request.get_param_value("project"));
    v1::AtlasService::Stub stub(gateway.channel());
    stream->reader = stub.Watch(&stream->context, watch);
    if (!stream->reader->Read(&stream->event)) {
      const grpc::Status status = stream->reader->Finish();
      CloseStream(&stream->context);
      SendError(response, status.ok() ? grpc::StatusCode::INTERNAL : status.error_code(),
                status.ok() ? "the watch ended at once" : status.error_message());
      return;
    }
    stream->pending = true;
    response.set_header("Cache-Control", "no-store");
    response.set_chunked_content_provider(
        "text/event-stream",
        [stream](std::size_t offset, httplib::DataSink& sink) {
          // Reconnect after a second when the stream ends.
          if (offset == 0 && !sink.write("retry: 1000\n\n", 13)) return false;
          if (!stream->pending && !stream->reader->Read(&stream->event)) {
            sink.done();
            return true;
          }
          stream->pending = false;
          google::protobuf::util::JsonPrintOptions print;
          print.preserve_proto_field_names = true;
          std::string json;
          (void)google::protobuf::util::MessageToJsonString(stream->event, &json, print);
          const std::string line = "data: " + json + "\n\n";
          return sink.write(line.data(), line.size());
        },
        [stream](bool /*success*/) {
          stream->context.TryCancel();
          (void)stream->reader->Finish();
          stream->state->CloseStream(&stream->context);
        });
  }

  // A DataChunk stream of a gRPC download (DownloadResult,
  // DownloadSurfaces), sent on as it is read.
  struct ChunkStream {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReader<v1::DataChunk>> reader;
    v1::DataChunk chunk;
    bool pending = false;  // chunk read and not yet sent
  };

  // Answers with what `stream` reads, as `type` (with a Content-Disposition
  // unless `disposition` is empty). The first chunk decides the answer: an
  // error, or the size.
  void SendChunks(const std::shared_ptr<ChunkStream>& stream, const std::string& type,
                  const std::string& disposition, httplib::Response& response) {
    if (!stream->reader->Read(&stream->chunk)) {
      const grpc::Status status = stream->reader->Finish();
      SendError(response, status.ok() ? grpc::StatusCode::INTERNAL : status.error_code(),
                status.ok() ? "the file came without data" : status.error_message());
      return;
    }
    stream->pending = true;
    const std::size_t total =
        static_cast<std::size_t>(std::max<int64_t>(0, stream->chunk.total_size()));
    if (!disposition.empty()) response.set_header("Content-Disposition", disposition);
    response.set_header("Cache-Control", "no-store");
    response.set_content_provider(
        total, type.c_str(),
        [stream](std::size_t /*offset*/, std::size_t /*length*/, httplib::DataSink& sink) {
          if (!stream->pending && !stream->reader->Read(&stream->chunk)) return false;
          stream->pending = false;
          const std::string& data = stream->chunk.data();
          return sink.write(data.data(), data.size());
        },
        [stream](bool /*success*/) {
          stream->context.TryCancel();
          (void)stream->reader->Finish();
        });
  }

  void Download(const httplib::Request& request, httplib::Response& response) {
    std::string token;
    if (!SessionOf(request, response, &token)) return;
    auto stream = std::make_shared<ChunkStream>();
    stream->context.AddMetadata("authorization", "Bearer " + token);
    v1::DownloadResultRequest download;
    download.set_job_id(request.matches[1].str());
    download.set_file(request.matches[2].str());
    v1::JobService::Stub stub(gateway.channel());
    stream->reader = stub.DownloadResult(&stream->context, download);
    const std::string name = request.matches[2].str();
    SendChunks(stream, ContentType(name), "attachment; filename=\"" + name + "\"", response);
  }

  // A project's structures' surfaces (glTF binary) from DownloadSurfaces:
  // ?project=P and either &snapshot=ID_OR_TAG or &structure=S[&revision=N].
  void Surfaces(const httplib::Request& request, httplib::Response& response) {
    std::string token;
    if (!SessionOf(request, response, &token)) return;
    v1::DownloadSurfacesRequest surfaces;
    surfaces.set_project(request.get_param_value("project"));
    surfaces.set_snapshot(request.get_param_value("snapshot"));
    surfaces.set_structure(request.get_param_value("structure"));
    const std::string revision = request.get_param_value("revision");
    if (!revision.empty()) {
      static const std::regex kNumber("[0-9]{1,18}");
      if (!std::regex_match(revision, kNumber)) {
        SendError(response, grpc::StatusCode::INVALID_ARGUMENT,
                  "revision: '" + revision.substr(0, 40) + "' is not a revision number");
        return;
      }
      surfaces.set_revision(std::stoll(revision));
    }
    auto stream = std::make_shared<ChunkStream>();
    stream->context.AddMetadata("authorization", "Bearer " + token);
    v1::AtlasService::Stub stub(gateway.channel());
    stream->reader = stub.DownloadSurfaces(&stream->context, surfaces);
    SendChunks(stream, "model/gltf-binary", "", response);
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
  // Every event stream holds a thread: room for the rest beside them.
  const int threads = std::max(1, options.threads) + kMaxEventStreams;
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
    std::string token, user;
    if (!state.SessionOf(request, response, &token)) return;
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

  // A result file of a job the caller may see, streamed from DownloadResult
  // (a plain GET, so that a link downloads it; the cookie is not sent by
  // other sites' requests, and a browser's cross-site mark is refused).
  http.Get(R"(/api/jobs/([A-Za-z0-9]+)/files/([A-Za-z0-9._-]+))",
           [&state](const httplib::Request& request, httplib::Response& response) {
             state.Download(request, response);
           });

  // The structures' surfaces, built on the server (a GET, so that the 3D
  // view's loader fetches it as a file).
  http.Get("/api/surfaces", [&state](const httplib::Request& request, httplib::Response& response) {
    state.Surfaces(request, response);
  });

  http.Get("/api/events", [&state](const httplib::Request& request, httplib::Response& response) {
    state.Events(request, response);
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
  if (state_ != nullptr) state_->CancelStreams();
  if (http_ != nullptr) http_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace pba
