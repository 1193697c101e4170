// idrig-catalog: see services/catalog/catalog_service.h. Config: deploy/config/catalog.json.
#include "services/catalog/catalog_service.h"
#include "services/common/service_main.h"

int main(int argc, char** argv) {
  return idrig::RunServiceMain<idrig::CatalogService, idrig::CatalogConfig>(
      argc, argv, "idrig-catalog", "stores identified models idempotently and acknowledges them",
      {{"--db", "db_path", "catalogue (SQLite file)"}}, 50);
}
