// SHA-256 (OpenSSL's EVP interface), the one implementation for every
// program: structure-set files and manifests, the atlas mesh cache, blobs
// and uploads in the store, result files, the client's downloads, tokens
// kept only as hashes. Part of pba_base, which has no solver in it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "pba/status.h"

struct evp_md_ctx_st;

namespace pba {

using Sha256Digest = std::array<unsigned char, 32>;

// A digest fed in pieces (a mapped file in windows, a file in blocks).
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  // False once OpenSSL failed (out of memory); Finish then fails too.
  bool Update(const void* data, std::size_t size);
  // kInternal when OpenSSL failed at any step.
  Status Finish(Sha256Digest* digest);

 private:
  struct Free {
    void operator()(evp_md_ctx_st* context) const;
  };
  std::unique_ptr<evp_md_ctx_st, Free> context_;
  bool ok_ = false;
};

Sha256Digest Sha256Of(const void* data, std::size_t size);

// Lowercase hex, 64 characters.
std::string HexOf(const Sha256Digest& digest);
// Lowercase hex of `count` bytes (2 * count characters).
std::string HexOf(const unsigned char* bytes, std::size_t count);

// Lowercase hex SHA-256 (64 characters) of `bytes`.
std::string Sha256Hex(std::string_view bytes);

// Whether `text` has the form of Sha256Hex's output: 64 characters 0-9 a-f.
bool IsSha256Hex(std::string_view text);

// Lowercase hex SHA-256 of a file's bytes, read in blocks (a label volume
// may be hundreds of megabytes), and its size when `size` is given. kIo
// naming the file when it cannot be read.
Status FileSha256Hex(const std::filesystem::path& path, std::string* hex, int64_t* size = nullptr);

}  // namespace pba
