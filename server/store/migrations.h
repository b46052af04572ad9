// The schema of pba.db as an ordered list of migrations. A migration is never
// edited once released: a schema change is a new entry at the end. Each one
// runs in its own transaction together with its schema_version row, so a
// crash leaves the database at a whole version.
#pragma once

#include "pba/status.h"
#include "store/database.h"

namespace pba {

// The version a fully migrated database has.
int LatestSchemaVersion();

// Brings `db` to LatestSchemaVersion(). Refuses a database written by a newer
// server (a version above the latest known) rather than guess at its schema.
// `up_to` > 0 stops at that version (for tests of an upgrade).
Status ApplyMigrations(Database& db, int up_to = 0);

// The highest applied version; 0 for a new database.
Status ReadSchemaVersion(Database& db, int* version);

}  // namespace pba
