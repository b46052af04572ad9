// WebServer: pba-server --http HOST:PORT. A small web application (its
// files in the server's install folder, three.js and Chart.js from
// Debian's packages) and a JSON API over HTTP that is a gateway to the
// server's own gRPC services: every API call is the gRPC call of the same
// name, made in-process (grpc::Server::InProcessChannel) with the caller's
// token as its `authorization: Bearer` metadata, so authentication, roles,
// bounds and every rule are the gRPC services' own; nothing is decided
// twice.
//
// Sign-in: POST /api/session {"token": ...} checks the token (WhoAmI) and
// keeps it in a cookie the page's scripts cannot read (HttpOnly,
// SameSite=Strict, Secure under TLS); it answers the user and a CSRF token
// derived from the access token and a secret of this server start. Every
// API call is a POST carrying that CSRF token in the X-PBA-CSRF header,
// which a page of another site can neither read nor send without a CORS
// preflight this server never grants; a request whose Origin is not this
// server's is refused as well. A request without the cookie sees nothing
// (401).
//
// Routes:
//   GET  /                         the application (index.html)
//   GET  /app/NAME                 its other files (a fixed list read at start)
//   GET  /vendor/NAME              three.js, its OrbitControls and
//                                  GLTFLoader, Chart.js (a fixed map)
//   GET|POST|DELETE /api/session   who is signed in; sign in; sign out
//   GET  /api/events?project=P     the project's changes as server-sent
//                                  events (AtlasService.Watch), at most 16
//                                  streams at once, each a minute (the
//                                  browser reopens it)
//   GET  /api/jobs/ID/files/NAME   a result file (JobService.DownloadResult)
//   POST /api/v1/SERVICE/METHOD    the gRPC call (web_gateway.h lists which),
//                                  its request and response as protobuf JSON;
//                                  errors as {"code", "message"} with the
//                                  HTTP status of the gRPC code
#pragma once

#include <grpcpp/channel.h>

#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "pba/status.h"

namespace httplib {
class Server;
}

namespace pba {

struct WebOptions {
  // HOST:PORT; port 0 picks a free port (WebServer::address()).
  std::string listen = "127.0.0.1:8080";
  // The application's files (index.html, app.js, ...).
  std::filesystem::path app_dir;
  // Debian's JavaScript packages (libjs-three, libjs-chart.js).
  std::filesystem::path vendor_dir = "/usr/share/javascript";
  // PEM certificate chain and key files: both set, HTTPS only; both
  // empty: HTTP.
  std::filesystem::path tls_cert, tls_key;
  // Requests served at once (each server-sent event stream holds one).
  int threads = 32;
};

// The request body bound of every API call.
inline constexpr std::size_t kWebMaxBody = std::size_t{1} << 20;

class WebServer {
 public:
  // Listens and serves on its own threads; `channel` reaches the gRPC
  // services (PbaServer's in-process channel).
  static Status Start(const WebOptions& options, std::shared_ptr<grpc::Channel> channel,
                      std::unique_ptr<WebServer>* out);
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;
  ~WebServer();  // Stop()

  // HOST:PORT actually listened on.
  const std::string& address() const { return address_; }
  // Stops listening and waits for the requests in flight. Idempotent.
  void Stop();

 private:
  WebServer() = default;
  struct State;  // the routes' shared state, defined in the .cc

  std::unique_ptr<State> state_;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
  std::string address_;
};

}  // namespace pba
