// Validates a .glb or .gltf file (and the buffers and images it names) with the Khronos glTF
// validator, the npm package `gltf-validator` installed in tools/gltf-validator:
//
//   npm ci --prefix tools/gltf-validator
//   node scripts/gltf-validate.mjs head.glb
//
// Prints one JSON line on stdout: the counts of errors, warnings, infos and hints, the validator's
// version and the first issues (code, severity, pointer, message). Exits 0 when the file has no
// errors, 1 when it has some, 2 when it cannot be validated (missing file or package).
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const tools = path.join(here, "..", "tools", "gltf-validator");

async function main() {
  const file = process.argv[2];
  if (!file) {
    console.error("usage: node scripts/gltf-validate.mjs FILE.glb|FILE.gltf");
    return 2;
  }
  let validator;
  try {
    validator = createRequire(path.join(tools, "package.json"))("gltf-validator");
  } catch (e) {
    console.error(`gltf-validator is not installed: run npm ci --prefix ${tools} (${e.message})`);
    return 2;
  }
  const bytes = await readFile(file);
  const folder = path.dirname(path.resolve(file));
  const report = await validator.validateBytes(new Uint8Array(bytes), {
    uri: path.basename(file),
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: (uri) => readFile(path.resolve(folder, decodeURIComponent(uri))),
  });
  const issues = report.issues;
  const summary = {
    file,
    validator: report.validatorVersion,
    numErrors: issues.numErrors,
    numWarnings: issues.numWarnings,
    numInfos: issues.numInfos,
    numHints: issues.numHints,
    messages: issues.messages.slice(0, 20),
  };
  console.log(JSON.stringify(summary));
  return issues.numErrors === 0 ? 0 : 1;
}

main().then(
  (code) => process.exit(code),
  (error) => {
    console.error(`cannot validate ${process.argv[2]}: ${error}`);
    process.exit(2);
  },
);
