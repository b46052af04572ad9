// Helpers shared by the pba-server tests: a temporary directory (temp_dir.h) and a fake
// pba-solve (a shell script) whose behaviour is chosen by the scene's name.
#pragma once

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>

#include "pba/v1/scene.pb.h"
#include "unit/server/temp_dir.h"

namespace pba::testing {

// The content of result.h5 written by the fake solver for a scene named
// "big": 2.5 MiB, so downloads need several chunks.
constexpr int kBigResultBytes = 5 * 512 * 1024;

// Writes the fake solver into `dir` and returns its path. It follows the
// pba-solve contract (SCENE --out DIR --progress=json) and acts on the scene
// name (exit codes as pba-solve's, core/exit_codes.h):
//   ok / big   progress lines, then a result dir (result.h5 = "hello\n" or
//              kBigResultBytes bytes, result.xdmf, summary.json, and the
//              staged snapshot's manifest.json when there is one), exit 0
//   throttle   progress 0.10 0.11 0.12 0.20 in one phase, then as ok
//   error      an ERROR line with a field, exit 11 (numerical)
//   exit13     exit 13 (io) without an ERROR line
//   killed     kills itself with SIGKILL
//   slow       progress, then sleeps until SIGTERM (exits 7, cancelled)
//   stubborn   ignores SIGTERM, sleeps until killed
//   partial    half-writes a result in its hidden staging sibling
//              (.result.partial-PID), then sleeps; SIGTERM ends it there
//              (exit 7) without removing it, as pba-solve's cancel watchdog
//              does
inline std::filesystem::path WriteFakeSolver(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "fake-pba-solve";
  std::ofstream script(path);
  script << R"sh(#!/bin/sh
scene="$1"
out="$3"
name=$(sed -n 's/.*"name": *"\([^"]*\)".*/\1/p' "$scene" | head -n 1)
echo "fake pba-solve: scene $name" >&2
echo "fake pba-solve: arguments $*" >&2
progress() { echo "{\"kind\":\"PROGRESS\",\"phase\":\"$1\",\"progress\":$2,\"message\":\"$3\"}"; }
succeed() {
  progress write 0.9 "writing"
  tmp="$(dirname "$out")/.result.partial-$$"
  mkdir -p "$tmp"
  if [ "$name" = big ]; then
    head -c )sh"
         << kBigResultBytes << R"sh( /dev/zero | tr '\0' 'x' > "$tmp/result.h5"
  else
    printf 'hello\n' > "$tmp/result.h5"
  fi
  echo '<Xdmf/>' > "$tmp/result.xdmf"
  staged="$(dirname "$scene")/snapshot/manifest.json"
  if [ -f "$staged" ]; then cp "$staged" "$tmp/manifest.json"; fi
  echo "{\"scene_name\":\"$name\",\"modelled\":{\"nodes\":\"27\"},\"future_field\":1}" > "$tmp/summary.json"
  (cd "$tmp" && sha256sum * > SHA256SUMS)
  # A file lost or changed after pba-solve listed it (on the way to the
  # server, say), or one it did not write.
  case "$name" in
    damaged) printf 'hel' > "$tmp/result.h5" ;;
    lost) rm "$tmp/result.xdmf" ;;
    stray) echo extra > "$tmp/stray.txt" ;;
    unlisted) rm "$tmp/SHA256SUMS" ;;
  esac
  mv "$tmp" "$out"
  echo "{\"kind\":\"DONE\",\"message\":\"$out\"}"
  exit 0
}
case "$name" in
  ok|big|damaged|lost|stray|unlisted)
    progress mesh 0.1 "meshing"
    echo "not json at all"
    progress solve 0.5 "solving"
    succeed ;;
  throttle)
    progress solve 0.10 a
    progress solve 0.11 b
    progress solve 0.12 c
    progress solve 0.20 d
    succeed ;;
  error)
    progress assemble 0.2 "assembling"
    echo '{"kind":"ERROR","code":"NUMERICAL","field":"material.linear_elastic","message":"stiffness matrix is singular"}'
    exit 11 ;;
  exit13)
    exit 13 ;;
  killed)
    progress mesh 0.1 "meshing"
    kill -KILL $$ ;;
  slow)
    trap 'exit 7' TERM
    progress mesh 0.1 "meshing"
    i=0
    while [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done
    exit 0 ;;
  partial)
    trap 'exit 7' TERM
    tmp="$(dirname "$out")/.result.partial-$$"
    mkdir -p "$tmp"
    printf 'half' > "$tmp/result.h5"
    progress write 0.9 "writing"
    i=0
    while [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done
    exit 0 ;;
  stubborn)
    trap '' TERM
    progress mesh 0.1 "meshing"
    i=0
    while [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done
    exit 0 ;;
esac
echo "unknown scene $name" >&2
exit 1
)sh";
  script.close();
  ::chmod(path.c_str(), 0755);
  return path;
}

// An atlas scene that passes validation, named `name`: two structures of
// the atlas its source names (empty: a snapshot's), surface fixed.
inline v1::Scene AtlasScene(const std::string& name) {
  v1::Scene scene;
  scene.set_name(name);
  scene.mutable_geometry()->mutable_atlas()->set_voxel_size_mm(2);
  scene.mutable_mesh()->set_element_size_mm(4);
  auto* material = scene.mutable_material();
  material->set_name("tissue");
  material->mutable_linear_elastic()->set_youngs_modulus_pa(3000);
  material->mutable_linear_elastic()->set_poissons_ratio(0.45);
  auto* fixed = scene.add_boundary_conditions();
  fixed->set_set("surface");
  fixed->mutable_fixed();
  return scene;
}

// A scene that passes validation, named `name`.
inline v1::Scene ValidScene(const std::string& name) {
  v1::Scene scene;
  scene.set_name(name);
  auto* box = scene.mutable_geometry()->mutable_box();
  box->add_size_mm(10);
  box->add_size_mm(10);
  box->add_size_mm(20);
  auto* material = scene.mutable_material();
  material->set_name("tissue");
  material->mutable_linear_elastic()->set_youngs_modulus_pa(3000);
  material->mutable_linear_elastic()->set_poissons_ratio(0.45);
  auto* fixed = scene.add_boundary_conditions();
  fixed->set_set("bottom");
  fixed->mutable_fixed();
  auto* pushed = scene.add_boundary_conditions();
  pushed->set_set("top");
  pushed->mutable_displacement()->set_z_mm(-1);
  return scene;
}

// Polls `done` every 20 ms for up to `timeout`.
inline bool WaitUntil(const std::function<bool()>& done,
                      std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

}  // namespace pba::testing
