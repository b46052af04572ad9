#include "core/sha256.h"

#include <openssl/evp.h>

#include <fstream>
#include <vector>

namespace pba {

void Sha256::Free::operator()(evp_md_ctx_st* context) const { EVP_MD_CTX_free(context); }

Sha256::Sha256() : context_(EVP_MD_CTX_new()) {
  ok_ = context_ != nullptr && EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr) == 1;
}

Sha256::~Sha256() = default;

bool Sha256::Update(const void* data, std::size_t size) {
  if (ok_ && size > 0) ok_ = EVP_DigestUpdate(context_.get(), data, size) == 1;
  return ok_;
}

Status Sha256::Finish(Sha256Digest* digest) {
  unsigned int length = 0;
  if (!ok_ || EVP_DigestFinal_ex(context_.get(), digest->data(), &length) != 1 ||
      length != digest->size()) {
    ok_ = false;
    return Status::Internal("cannot compute SHA-256");
  }
  ok_ = false;  // finished: a digest is taken once
  return Status::Ok();
}

Sha256Digest Sha256Of(const void* data, std::size_t size) {
  Sha256Digest digest{};
  unsigned int length = 0;
  EVP_Digest(data, size, digest.data(), &length, EVP_sha256(), nullptr);
  return digest;
}

std::string HexOf(const unsigned char* bytes, std::size_t count) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * count);
  for (std::size_t i = 0; i < count; ++i) {
    hex.push_back(kDigits[bytes[i] >> 4]);
    hex.push_back(kDigits[bytes[i] & 15]);
  }
  return hex;
}

std::string HexOf(const Sha256Digest& digest) { return HexOf(digest.data(), digest.size()); }

std::string Sha256Hex(std::string_view bytes) {
  return HexOf(Sha256Of(bytes.data(), bytes.size()));
}

bool IsSha256Hex(std::string_view text) {
  if (text.size() != 64) return false;
  for (char c : text) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

Status FileSha256Hex(const std::filesystem::path& path, std::string* hex, int64_t* size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot read " + path.string());
  Sha256 sha;
  std::vector<char> buffer(1 << 20);
  int64_t total = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    if (in.gcount() > 0) {
      sha.Update(buffer.data(), static_cast<std::size_t>(in.gcount()));
      total += in.gcount();
    }
  }
  if (in.bad()) return Status::Io("reading " + path.string() + " failed");
  Sha256Digest digest{};
  PBA_RETURN_IF_ERROR(sha.Finish(&digest));
  *hex = HexOf(digest);
  if (size != nullptr) *size = total;
  return Status::Ok();
}

}  // namespace pba
