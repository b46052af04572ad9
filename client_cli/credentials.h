// Where `pba` keeps the access tokens `pba login` stored: one line
// "<server> <token>" per server in $XDG_CONFIG_HOME/pba/credentials (else
// ~/.config/pba/credentials), owner-only (0600). PBA_TOKEN, when set,
// overrides the file.
#pragma once

#include <filesystem>
#include <string>

namespace pba::cli {

std::filesystem::path CredentialsPath();

// The token for `server`: PBA_TOKEN, else the credentials file's entry;
// "" when there is none.
std::string FindToken(const std::string& server);

// Stores (replaces) the token for `server`; false with *error on failure.
bool StoreToken(const std::string& server, const std::string& token, std::string* error);

// Removes the token for `server`; true when there was one.
bool ForgetToken(const std::string& server, std::string* error);

}  // namespace pba::cli
