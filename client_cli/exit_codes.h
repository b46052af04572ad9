// Exit codes of `pba`: the table pba, pba-solve and pba-atlas share
// (core/exit_codes.h; docs/cli.md lists them for scripts). The client's
// code, in namespace pba::cli, names them unqualified (kExitNotReady).
#pragma once

#include "core/exit_codes.h"
