// Writes Foxglove's message schemas as .proto files (foxglove/<Name>.proto under OUT_DIR) with the
// generator that ships in @foxglove/schemas itself (dist/internal/generateProto.js), the one the
// foxglove-sdk repository runs to produce its schemas/proto tree. Schemas that are protobuf
// well-known types (Timestamp, Duration) are imported from google/protobuf instead.
// usage: node generate_protos.js OUT_DIR
"use strict";
const fs = require("fs");
const path = require("path");

const out = process.argv[2];
if (!out) {
  console.error("usage: node generate_protos.js OUT_DIR");
  process.exit(2);
}
const pkg = path.dirname(require.resolve("@foxglove/schemas/package.json"));
const { foxgloveMessageSchemas, foxgloveEnumSchemas } = require(path.join(pkg, "dist/internal/schemas.js"));
const { generateProto } = require(path.join(pkg, "dist/internal/generateProto.js"));

fs.mkdirSync(path.join(out, "foxglove"), { recursive: true });
let written = 0;
for (const schema of Object.values(foxgloveMessageSchemas)) {
  if (schema.protoEquivalent != undefined) continue;
  const enums = Object.values(foxgloveEnumSchemas).filter((e) => e.parentSchemaName === schema.name);
  fs.writeFileSync(path.join(out, "foxglove", `${schema.name}.proto`), generateProto(schema, enums));
  ++written;
}
console.log(`generate_protos: ${written} schemas of @foxglove/schemas ${require(path.join(pkg, "package.json")).version}`);
