// pba-server --http: the web view's files and its JSON API, through a real
// server on loopback and a plain HTTP client (cpp-httplib's), as a browser
// would call it and as a hostile page would try to: no session sees
// nothing, a request without the session's CSRF token or from another
// site is refused, and roles are the gRPC services' own.
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "common/subprocess.h"
#include "integration/block_scene.h"
#include "integration/server_fixture.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;

class WebTest : public ServerTest {
 protected:
  std::vector<std::string> ServerArgs() const override { return {"--http", "127.0.0.1:0"}; }

  void SetUp() override {
    ServerTest::SetUp();
    const std::string json = ReadFile(dir_.path() / "data" / "server.json");
    std::smatch match;
    ASSERT_TRUE(std::regex_search(json, match, std::regex("\"http\":\"127.0.0.1:([0-9]+)\"")))
        << json;
    port_ = std::stoi(match[1].str());
    std::ifstream(dir_.path() / "data" / "admin.token") >> admin_;
  }

  httplib::Client Client() {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(30, 0);
    return client;
  }
  std::string Origin() const { return "http://127.0.0.1:" + std::to_string(port_); }

  // Signs in with `token`: the session's cookie and CSRF token.
  bool SignIn(const std::string& token, std::string* cookie, std::string* csrf) {
    auto client = Client();
    const auto response = client.Post("/api/session", {{"Origin", Origin()}},
                                      "{\"token\":\"" + token + "\"}", "application/json");
    if (!response || response->status != 200) return false;
    std::smatch match;
    const std::string set = response->get_header_value("Set-Cookie");
    if (!std::regex_search(set, match, std::regex("^(pba_token=[^;]+)"))) return false;
    *cookie = match[1].str();
    if (!std::regex_search(response->body, match, std::regex("\"csrf\":\"([0-9a-f]{64})\"")))
      return false;
    *csrf = match[1].str();
    return true;
  }

  // An API call with the session, from this site; the response.
  httplib::Result Call(const std::string& name, const std::string& body, const std::string& cookie,
                       const std::string& csrf) {
    auto client = Client();
    return client.Post("/api/v1/" + name,
                       {{"Cookie", cookie}, {"X-PBA-CSRF", csrf}, {"Origin", Origin()}}, body,
                       "application/json");
  }

  int port_ = 0;
  std::string admin_;
};

// The page, its script and the Debian packages' three.js and Chart.js are
// served from memory, with a content security policy; nothing else is.
TEST_F(WebTest, ServesTheApplicationAndDebiansLibrariesAndNothingElse) {
  auto client = Client();
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/app/app.js"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'self'"),
            std::string::npos);
  EXPECT_EQ(page->get_header_value("X-Frame-Options"), "DENY");
  const auto script = client.Get("/app/app.js");
  ASSERT_TRUE(script);
  EXPECT_EQ(script->status, 200);
  EXPECT_NE(script->get_header_value("Content-Type").find("text/javascript"), std::string::npos);
  const auto three = client.Get("/vendor/three.module.js");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->status, 200);
  EXPECT_NE(three->body.find("REVISION"), std::string::npos);
  for (const char* path :
       {"/vendor/chart.min.js", "/vendor/OrbitControls.js", "/vendor/GLTFLoader.js"}) {
    const auto file = client.Get(path);
    ASSERT_TRUE(file) << path;
    EXPECT_EQ(file->status, 200) << path;
    // three.js's examples import it where this server serves it.
    EXPECT_EQ(file->body.find("../build/three.module.js"), std::string::npos) << path;
  }
  const auto controls = client.Get("/vendor/OrbitControls.js");
  ASSERT_TRUE(controls);
  EXPECT_NE(controls->body.find("from \"/vendor/three.module.js\""), std::string::npos);
  for (const char* path : {"/app/../pba.db", "/app/%2e%2e/pba.db", "/pba.db", "/vendor/three.js",
                           "/app/missing.js", "/data/admin.token"}) {
    const auto file = client.Get(path);
    ASSERT_TRUE(file) << path;
    EXPECT_EQ(file->status, 404) << path;
    EXPECT_EQ(file->body.find(admin_), std::string::npos) << path;
  }
}

// Without a session nothing is answered; a token that is no user's, or no
// token at all, does not make one.
TEST_F(WebTest, NoTokenSeesNothing) {
  auto client = Client();
  const auto listed = client.Post("/api/v1/AtlasService/ListProjects", "{}", "application/json");
  ASSERT_TRUE(listed);
  EXPECT_EQ(listed->status, 401);
  EXPECT_NE(listed->body.find("\"code\":\"UNAUTHENTICATED\""), std::string::npos) << listed->body;
  const auto session = client.Get("/api/session");
  ASSERT_TRUE(session);
  EXPECT_EQ(session->status, 401);
  std::string cookie, csrf;
  EXPECT_FALSE(SignIn(std::string(64, 'a'), &cookie, &csrf));
  const auto wrong = client.Post("/api/session", "{\"token\":\"" + std::string(64, 'a') + "\"}",
                                 "application/json");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 401) << wrong->body;
  EXPECT_FALSE(wrong->has_header("Set-Cookie"));
  const auto garbled = client.Post("/api/session", "{\"token\": 7}", "application/json");
  ASSERT_TRUE(garbled);
  EXPECT_EQ(garbled->status, 400) << garbled->body;
  const auto forged_cookie = client.Post(
      "/api/v1/AtlasService/ListProjects",
      {{"Cookie", "pba_token=" + std::string(64, 'b')}, {"X-PBA-CSRF", std::string(64, '0')}}, "{}",
      "application/json");
  ASSERT_TRUE(forged_cookie);
  EXPECT_EQ(forged_cookie->status, 403) << forged_cookie->body;  // no CSRF token of it
}

// A sign-in keeps the token in a cookie scripts cannot read and no other
// site's request carries; the API then answers what gRPC answers.
TEST_F(WebTest, SignInKeepsTheTokenInAStrictHttpOnlyCookie) {
  auto client = Client();
  const auto signed_in = client.Post("/api/session", {{"Origin", Origin()}},
                                     "{\"token\":\"" + admin_ + "\"}", "application/json");
  ASSERT_TRUE(signed_in);
  ASSERT_EQ(signed_in->status, 200) << signed_in->body;
  const std::string set = signed_in->get_header_value("Set-Cookie");
  EXPECT_NE(set.find("HttpOnly"), std::string::npos) << set;
  EXPECT_NE(set.find("SameSite=Strict"), std::string::npos) << set;
  EXPECT_NE(signed_in->body.find("\"name\":\"admin\""), std::string::npos) << signed_in->body;
  EXPECT_EQ(signed_in->body.find(admin_), std::string::npos) << "the token is not in the body";

  std::string cookie, csrf;
  ASSERT_TRUE(SignIn(admin_, &cookie, &csrf));
  ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
  const auto projects = Call("AtlasService/ListProjects", "{}", cookie, csrf);
  ASSERT_TRUE(projects);
  EXPECT_EQ(projects->status, 200) << projects->body;
  EXPECT_NE(projects->body.find("\"name\":\"demo\""), std::string::npos) << projects->body;
  const auto info = Call("JobService/GetServerInfo", "", cookie, csrf);
  ASSERT_TRUE(info);
  EXPECT_NE(info->body.find("\"executor\":\"local\""), std::string::npos) << info->body;
  const auto bad = Call("AtlasService/ListStructures", "{\"projekt\":\"demo\"}", cookie, csrf);
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400) << bad->body;
  EXPECT_NE(bad->body.find("projekt"), std::string::npos) << bad->body;

  const auto out = client.Delete("/api/session", {{"Origin", Origin()}, {"Cookie", cookie}});
  ASSERT_TRUE(out);
  EXPECT_NE(out->get_header_value("Set-Cookie").find("Max-Age=0"), std::string::npos);
}

// A forged request: no CSRF token, another site's Origin, a browser's
// cross-site mark, a sign-in from another site; and calls the web may not
// make at all (geometry is changed with the CLI).
TEST_F(WebTest, ForgedCrossSiteRequestsAreRefused) {
  std::string cookie, csrf;
  ASSERT_TRUE(SignIn(admin_, &cookie, &csrf));
  auto client = Client();
  const std::string body = "{\"name\":\"forged\"}";
  const std::vector<httplib::Headers> forged = {
      {{"Cookie", cookie}},
      {{"Cookie", cookie}, {"X-PBA-CSRF", std::string(64, '0')}},
      {{"Cookie", cookie}, {"X-PBA-CSRF", csrf}, {"Origin", "http://evil.example"}},
      {{"Cookie", cookie}, {"X-PBA-CSRF", csrf}, {"Sec-Fetch-Site", "cross-site"}},
  };
  for (const httplib::Headers& headers : forged) {
    const auto refused =
        client.Post("/api/v1/AtlasService/ListProjects", headers, "{}", "application/json");
    ASSERT_TRUE(refused);
    EXPECT_EQ(refused->status, 403) << refused->body;
    EXPECT_NE(refused->body.find("PERMISSION_DENIED"), std::string::npos) << refused->body;
  }
  const auto login_forged = client.Post("/api/session", {{"Origin", "http://evil.example"}},
                                        "{\"token\":\"" + admin_ + "\"}", "application/json");
  ASSERT_TRUE(login_forged);
  EXPECT_EQ(login_forged->status, 403);
  EXPECT_FALSE(login_forged->has_header("Set-Cookie"));
  for (const char* hidden :
       {"AtlasService/CommitStructure", "AtlasService/CreateProject", "AtlasService/BreakLock",
        "JobService/SubmitJob", "AtlasService/Nothing"}) {
    const auto refused = Call(hidden, body, cookie, csrf);
    ASSERT_TRUE(refused) << hidden;
    EXPECT_EQ(refused->status, 404) << hidden << ": " << refused->body;
  }
  EXPECT_EQ(Pba({"--json", "project", "list"}).out.find("forged"), std::string::npos);
}

// Roles are the gRPC services': a viewer of a project cannot take a lock
// in it from the page (PERMISSION_DENIED before the structure is looked
// for), its admin is told the structure does not exist.
TEST_F(WebTest, AViewerCannotTakeALockFromThePage) {
  ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
  const RunResult created = RunProcess(
      {PBA_SERVER_BIN, "admin", "create-user", "vera", "--data", (dir_.path() / "data").string()},
      seconds(30));
  ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
  std::smatch token;
  ASSERT_TRUE(std::regex_search(created.out, token, std::regex("[0-9a-f]{64}"))) << created.out;
  ASSERT_EQ(Pba({"project", "role", "demo", "vera", "viewer"}).exit_code, 0);

  std::string cookie, csrf;
  ASSERT_TRUE(SignIn(token.str(), &cookie, &csrf));
  const std::string lock = "{\"project\":\"demo\",\"structure\":\"Putamen\"}";
  const auto refused = Call("AtlasService/AcquireLock", lock, cookie, csrf);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403) << refused->body;
  const auto listed = Call("AtlasService/ListStructures", "{\"project\":\"demo\"}", cookie, csrf);
  ASSERT_TRUE(listed);
  EXPECT_EQ(listed->status, 200) << listed->body;

  std::string admin_cookie, admin_csrf;
  ASSERT_TRUE(SignIn(admin_, &admin_cookie, &admin_csrf));
  EXPECT_NE(admin_csrf, csrf);
  const auto missing = Call("AtlasService/AcquireLock", lock, admin_cookie, admin_csrf);
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404) << missing->body;
  // One session's CSRF token is not another's.
  const auto crossed = Call("AtlasService/ListProjects", "{}", cookie, admin_csrf);
  ASSERT_TRUE(crossed);
  EXPECT_EQ(crossed->status, 403);
}

// A finished job's files through the page's links: surfaces.glb (glTF
// binary of the mesh's surface), result.h5 byte for byte as the job lists
// it; nothing without a session or for a file the job does not have.
TEST_F(WebTest, AFinishedJobsFilesDownloadWithTheSession) {
  const fs::path scene = WriteScene("block.yaml", SmallBlockSceneYaml("block"));
  const RunResult submitted = Pba({"job", "submit", scene.string(), "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
  const std::string id = JobId(submitted);
  std::string cookie, csrf;
  ASSERT_TRUE(SignIn(admin_, &cookie, &csrf));
  const auto job = Call("JobService/GetJob", "{\"id\":\"" + id + "\"}", cookie, csrf);
  ASSERT_TRUE(job);
  ASSERT_EQ(job->status, 200) << job->body;
  std::smatch listed;
  ASSERT_TRUE(std::regex_search(
      job->body, listed, std::regex("\"name\":\"surfaces.glb\",\"size_bytes\":\"([0-9]+)\"")))
      << job->body;

  auto client = Client();
  const auto glb = client.Get("/api/jobs/" + id + "/files/surfaces.glb", {{"Cookie", cookie}});
  ASSERT_TRUE(glb);
  ASSERT_EQ(glb->status, 200) << glb->body;
  EXPECT_EQ(glb->get_header_value("Content-Type"), "model/gltf-binary");
  EXPECT_EQ(glb->body.substr(0, 4), "glTF");
  EXPECT_EQ(std::to_string(glb->body.size()), listed[1].str());
  EXPECT_NE(glb->body.find("\"_DISPLACEMENT\""), std::string::npos);
  EXPECT_NE(glb->body.find("\"name\":\"body\""), std::string::npos);

  const fs::path fetched = dir_.path() / "fetched";
  const RunResult fetch = Pba({"job", "fetch", id, "-o", fetched.string()});
  ASSERT_EQ(fetch.exit_code, 0) << fetch.out << fetch.err;
  const auto h5 = client.Get("/api/jobs/" + id + "/files/result.h5", {{"Cookie", cookie}});
  ASSERT_TRUE(h5);
  ASSERT_EQ(h5->status, 200);
  EXPECT_EQ(h5->body, ReadFile(fetched / "result.h5"));
  EXPECT_NE(h5->get_header_value("Content-Disposition").find("result.h5"), std::string::npos);

  const auto anonymous = client.Get("/api/jobs/" + id + "/files/result.h5");
  ASSERT_TRUE(anonymous);
  EXPECT_EQ(anonymous->status, 401);
  const auto cross = client.Get("/api/jobs/" + id + "/files/result.h5",
                                {{"Cookie", cookie}, {"Sec-Fetch-Site", "cross-site"}});
  ASSERT_TRUE(cross);
  EXPECT_EQ(cross->status, 403);
  for (const std::string& path : std::vector<std::string>{
           "/api/jobs/" + id + "/files/pba.db", "/api/jobs/jnosuchjob00/files/result.h5",
           "/api/jobs/" + id + "/files/..%2Fscene.yaml"}) {
    const auto missing = client.Get(path, {{"Cookie", cookie}});
    ASSERT_TRUE(missing) << path;
    EXPECT_EQ(missing->status, 404) << path << ": " << missing->body;
  }
}

// A project's changes as server-sent events: READY first, then a lock taken
// with the CLI, as the gRPC Watch sends them; no session, no stream; a
// project the caller is not a member of, the Watch's own refusal.
TEST_F(WebTest, AProjectsChangesStreamAsServerSentEvents) {
  ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
  const fs::path contours =
      WriteScene("putamen.json",
                 R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [5, 0], [5, 5], [0, 5]]]}]})");
  const RunResult created =
      Pba({"atlas", "create", "-p", "demo", "Putamen", contours.string(), "--colour", "1,2,3"});
  ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
  std::string cookie, csrf;
  ASSERT_TRUE(SignIn(admin_, &cookie, &csrf));

  std::string received, type;
  std::thread locker([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    Pba({"atlas", "lock", "-p", "demo", "Putamen"});
  });
  auto client = Client();
  const auto streamed = client.Get(
      "/api/events?project=demo", {{"Cookie", cookie}},
      [&](const httplib::Response& response) {
        type = response.get_header_value("Content-Type");
        return response.status == 200;
      },
      [&](const char* data, size_t size) {
        received.append(data, size);
        return received.find("LOCK_ACQUIRED") == std::string::npos;
      });
  locker.join();
  EXPECT_EQ(type, "text/event-stream");
  EXPECT_EQ(received.rfind("retry: 1000\n\n", 0), 0u) << received;
  const std::size_t ready = received.find("data: {\"kind\":\"READY\"");
  const std::size_t lock = received.find("\"kind\":\"LOCK_ACQUIRED\"");
  EXPECT_NE(ready, std::string::npos) << received;
  EXPECT_NE(lock, std::string::npos) << received;
  EXPECT_LT(ready, lock);
  EXPECT_NE(received.find("\"structure\":\"Putamen\""), std::string::npos) << received;

  const auto anonymous = client.Get("/api/events?project=demo");
  ASSERT_TRUE(anonymous);
  EXPECT_EQ(anonymous->status, 401);
  const RunResult vera = RunProcess(
      {PBA_SERVER_BIN, "admin", "create-user", "vera", "--data", (dir_.path() / "data").string()},
      seconds(30));
  std::smatch token;
  ASSERT_TRUE(std::regex_search(vera.out, token, std::regex("[0-9a-f]{64}"))) << vera.out;
  std::string vera_cookie, vera_csrf;
  ASSERT_TRUE(SignIn(token.str(), &vera_cookie, &vera_csrf));
  const auto stranger = client.Get("/api/events?project=demo", {{"Cookie", vera_cookie}});
  ASSERT_TRUE(stranger);
  EXPECT_TRUE(stranger->status == 403 || stranger->status == 404) << stranger->status;
}

// A glTF binary's nodes by name, each with the volume its triangles
// enclose [mm^3] and its box [mm] (positions are in metres).
struct GlbNode {
  double volume_mm3 = 0;
  std::array<double, 3> min{1e30, 1e30, 1e30}, max{-1e30, -1e30, -1e30};
};

bool ReadGlb(const std::string& glb, std::map<std::string, GlbNode>* nodes, std::string* why) {
  const auto u32 = [&](size_t at) {
    uint32_t v = 0;
    std::memcpy(&v, glb.data() + at, 4);
    return v;
  };
  if (glb.size() < 20 || glb.compare(0, 4, "glTF") != 0) return *why = "not glTF binary", false;
  const uint32_t json_size = u32(12);
  const std::string json = glb.substr(20, json_size);
  const size_t bin = 20 + json_size + 8;
  if (bin > glb.size()) return *why = "no binary chunk", false;
  google::protobuf::Struct root;
  if (!google::protobuf::util::JsonStringToMessage(json, &root).ok()) {
    return *why = "its JSON does not parse", false;
  }
  const auto& f = root.fields();
  const auto list = [&](const char* key) -> const auto& { return f.at(key).list_value().values(); };
  const auto number = [](const google::protobuf::Value& v, const char* key) {
    const auto& fields = v.struct_value().fields();
    const auto it = fields.find(key);
    return it == fields.end() ? 0.0 : it->second.number_value();
  };
  // An accessor's data: its count, and where its bytes start in `glb`.
  const auto data = [&](int accessor, size_t* count) {
    const auto& a = list("accessors")[accessor];
    const auto& view = list("bufferViews")[static_cast<int>(number(a, "bufferView"))];
    *count = static_cast<size_t>(number(a, "count"));
    return bin + static_cast<size_t>(number(view, "byteOffset") + number(a, "byteOffset"));
  };
  for (const auto& node : list("nodes")) {
    const std::string name = node.struct_value().fields().at("name").string_value();
    const auto& mesh = list("meshes")[static_cast<int>(number(node, "mesh"))];
    const auto& primitive = mesh.struct_value().fields().at("primitives").list_value().values(0);
    const auto& attributes = primitive.struct_value().fields().at("attributes");
    size_t vertices = 0, indices = 0;
    const size_t at = data(static_cast<int>(number(attributes, "POSITION")), &vertices);
    const size_t index_at = data(static_cast<int>(number(primitive, "indices")), &indices);
    if (index_at + 4 * indices > glb.size() || at + 12 * vertices > glb.size()) {
      return *why = name + "'s data runs past the file", false;
    }
    std::vector<std::array<double, 3>> x(vertices);
    GlbNode& out = (*nodes)[name];
    for (size_t v = 0; v < vertices; ++v) {
      float p[3];
      std::memcpy(p, glb.data() + at + 12 * v, 12);
      for (int k = 0; k < 3; ++k) {
        x[v][k] = 1e3 * p[k];
        out.min[k] = std::min(out.min[k], x[v][k]);
        out.max[k] = std::max(out.max[k], x[v][k]);
      }
    }
    for (size_t t = 0; t + 2 < indices; t += 3) {
      const uint32_t i = u32(index_at + 4 * t), j = u32(index_at + 4 * t + 4),
                     k = u32(index_at + 4 * t + 8);
      if (i >= vertices || j >= vertices || k >= vertices) return *why = "index past", false;
      const auto& a = x[i];
      const auto& b = x[j];
      const auto& c = x[k];
      out.volume_mm3 += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                         a[2] * (b[0] * c[1] - b[1] * c[0])) /
                        6;
    }
  }
  return true;
}

// Plate contours of a w x w mm square at x0, on plates from z = 0 to 20 mm
// every 5 mm.
std::string SquarePrism(double x0, double w) {
  std::string plates;
  for (int z = 0; z <= 20; z += 5) {
    plates += std::string(plates.empty() ? "" : ",") + "{\"z_mm\": " + std::to_string(z) +
              ", \"polygons\": [[[" + std::to_string(x0) + ", 0], [" + std::to_string(x0 + w) +
              ", 0], [" + std::to_string(x0 + w) + ", " + std::to_string(w) + "], [" +
              std::to_string(x0) + ", " + std::to_string(w) + "]]]}";
  }
  return "{\"plates\": [" + plates + "]}";
}

class WebSurfacesTest : public WebTest {
 protected:
  void SetUp() override {
    WebTest::SetUp();
    ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
    for (const auto& [name, x0, w] :
         {std::tuple<std::string, double, double>{"Block", 0, 20}, {"Slab", 30, 10}}) {
      const fs::path file = WriteScene(name + ".json", SquarePrism(x0, w));
      const RunResult made = Pba({"atlas", "create", "-p", "demo", name, file.string()});
      ASSERT_EQ(made.exit_code, 0) << made.out << made.err;
    }
    ASSERT_TRUE(SignIn(admin_, &cookie_, &csrf_));
  }

  httplib::Result Surfaces(const std::string& query, const std::string& cookie) {
    auto client = Client();
    client.set_read_timeout(120, 0);
    return client.Get("/api/surfaces?" + query, {{"Cookie", cookie}});
  }
  int LogCount(const std::string& text) {
    const std::string log = ReadFile(server_->log_path());
    int n = 0;
    for (size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++n;
    return n;
  }

  std::string cookie_, csrf_;
};

// A project's structures drawn from the server: one surface per structure,
// named as it, around its shape (the plates' prism: the square times the
// plates' span, less what the loft rounds off a small square's corners,
// as the server's own voxel measure of it says); the second view of the
// same shapes comes from the cache, and so does one after a colour change
// or of a snapshot of the same heads; one revision alone is drawn too.
TEST_F(WebSurfacesTest, AProjectsStructuresAreDrawnAsTheirShapesAndCached) {
  const auto first = Surfaces("project=demo", cookie_);
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 200) << first->body;
  EXPECT_EQ(first->get_header_value("Content-Type"), "model/gltf-binary");
  std::map<std::string, GlbNode> nodes;
  std::string why;
  ASSERT_TRUE(ReadGlb(first->body, &nodes, &why)) << why;
  ASSERT_EQ(nodes.size(), 2u);
  for (const auto& [name, x0, w] :
       {std::tuple<std::string, double, double>{"Block", 0, 20}, {"Slab", 30, 10}}) {
    ASSERT_EQ(nodes.count(name), 1u) << name;
    const GlbNode& node = nodes[name];
    const double prism = w * w * 20;
    EXPECT_NEAR(node.volume_mm3, prism, (w > 10 ? 0.03 : 0.15) * prism) << name;
    EXPECT_NEAR(node.min[0], x0, 1.5) << name;
    EXPECT_NEAR(node.max[0], x0 + w, 1.5) << name;
    EXPECT_NEAR(node.max[1], w, 1.5) << name;
  }
  EXPECT_EQ(LogCount("from the cache"), 0);

  const auto again = Surfaces("project=demo", cookie_);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->body, first->body);
  EXPECT_EQ(LogCount("from the cache"), 1);
  ASSERT_EQ(Pba({"atlas", "set", "-p", "demo", "Slab", "--colour", "10,200,30"}).exit_code, 0);
  ASSERT_EQ(Pba({"atlas", "snapshot", "create", "-p", "demo", "--name", "first"}).exit_code, 0);
  const auto snapshot = Surfaces("project=demo&snapshot=first", cookie_);
  ASSERT_TRUE(snapshot);
  ASSERT_EQ(snapshot->status, 200) << snapshot->body;
  EXPECT_EQ(snapshot->body, first->body);
  EXPECT_EQ(LogCount("from the cache"), 2);
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir_.path() / "data" / "cache" / "surfaces")) {
    entries += e.path().extension() == ".glb";
  }
  EXPECT_EQ(entries, 1);

  // One revision alone, for an overlay; a new shape is a new entry.
  const fs::path grown = WriteScene("grown.json", SquarePrism(30, 14));
  ASSERT_EQ(
      Pba({"atlas", "checkout", "-p", "demo", "Slab", "-o", (dir_.path() / "Slab.json").string()})
          .exit_code,
      0);
  fs::copy_file(grown, dir_.path() / "Slab.json", fs::copy_options::overwrite_existing);
  const RunResult committed =
      Pba({"atlas", "commit", (dir_.path() / "Slab.json").string(), "-m", "wider"});
  ASSERT_EQ(committed.exit_code, 0) << committed.out << committed.err;
  // Revision 2 is the colour's; 3 the new shape. Their volumes as the
  // server's own diff measures them on voxels.
  const auto diff = Call("AtlasService/DiffRevisions",
                         "{\"project\":\"demo\",\"structure\":\"Slab\",\"from_revision\":1,"
                         "\"to_revision\":3}",
                         cookie_, csrf_);
  ASSERT_TRUE(diff);
  std::smatch from, to;
  ASSERT_TRUE(std::regex_search(diff->body, from,
                                std::regex("\"shape\":\\{[^}]*\"from_volume_mm3\":([0-9.]+)")))
      << diff->body;
  ASSERT_TRUE(std::regex_search(diff->body, to,
                                std::regex("\"shape\":\\{[^}]*\"to_volume_mm3\":([0-9.]+)")));
  for (const auto& [revision, voxels] :
       {std::pair<std::string, double>{"1", std::stod(from[1].str())},
        {"0", std::stod(to[1].str())}}) {
    const auto alone = Surfaces("project=demo&structure=Slab&revision=" + revision, cookie_);
    ASSERT_TRUE(alone);
    ASSERT_EQ(alone->status, 200) << alone->body;
    std::map<std::string, GlbNode> one;
    ASSERT_TRUE(ReadGlb(alone->body, &one, &why)) << why;
    ASSERT_EQ(one.size(), 1u);
    EXPECT_NEAR(one["Slab"].volume_mm3, voxels, 0.05 * voxels) << "revision " << revision;
  }
  EXPECT_GT(std::stod(to[1].str()), 1.5 * std::stod(from[1].str()));
}

// Who may draw what, and requests that name nothing drawable, each with a
// clear refusal; a damaged cache entry is made again, never sent.
TEST_F(WebSurfacesTest, RefusalsAndADamagedCacheEntry) {
  auto client = Client();
  const auto anonymous = client.Get("/api/surfaces?project=demo");
  ASSERT_TRUE(anonymous);
  EXPECT_EQ(anonymous->status, 401);
  const RunResult created = RunProcess(
      {PBA_SERVER_BIN, "admin", "create-user", "olga", "--data", (dir_.path() / "data").string()},
      seconds(30));
  ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
  std::smatch token;
  ASSERT_TRUE(std::regex_search(created.out, token, std::regex("[0-9a-f]{64}"))) << created.out;
  std::string outsider, outsider_csrf;
  ASSERT_TRUE(SignIn(token.str(), &outsider, &outsider_csrf));
  const auto foreign = Surfaces("project=demo", outsider);
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->status, 403) << foreign->body;
  EXPECT_EQ(LogCount("DownloadSurfaces demo"), 0) << "nothing was built for an outsider";
  ASSERT_EQ(Pba({"project", "role", "demo", "olga", "viewer"}).exit_code, 0);
  const auto viewer = Surfaces("project=demo", outsider);
  ASSERT_TRUE(viewer);
  EXPECT_EQ(viewer->status, 200) << viewer->body;

  for (const auto& [query, status, says] : std::vector<std::tuple<std::string, int, std::string>>{
           {"project=demo&snapshot=nosuch", 404, "nosuch"},
           {"project=demo&structure=Nothing", 404, "Nothing"},
           {"project=demo&structure=Slab&revision=7", 404, "revision 7"},
           {"project=demo&structure=Slab&revision=x1", 400, "revision"},
           {"project=demo&revision=1", 400, "structure"},
           {"project=demo&structure=Slab&snapshot=1", 400, "snapshot"},
           {"project=nosuch", 404, "nosuch"}}) {
    const auto refused = Surfaces(query, cookie_);
    ASSERT_TRUE(refused) << query;
    EXPECT_EQ(refused->status, status) << query << ": " << refused->body;
    EXPECT_NE(refused->body.find(says), std::string::npos) << query << ": " << refused->body;
  }

  const fs::path cache = dir_.path() / "data" / "cache" / "surfaces";
  for (const auto& e : fs::directory_iterator(cache)) {
    std::ofstream(e.path(), std::ios::trunc) << "glTF but not really";
  }
  const auto remade = Surfaces("project=demo", cookie_);
  ASSERT_TRUE(remade);
  ASSERT_EQ(remade->status, 200) << remade->body;
  std::map<std::string, GlbNode> nodes;
  std::string why;
  EXPECT_TRUE(ReadGlb(remade->body, &nodes, &why)) << why;
  EXPECT_EQ(nodes.size(), 2u);
  EXPECT_EQ(LogCount("built in"), 2);
}

}  // namespace
}  // namespace pba::testing
