// Validates .glb files with the Khronos glTF validator (npm gltf-validator, the
// library: validateBytes) and prints one line per file: its path, then the
// numbers of errors, warnings, infos and hints, then each error and warning.
// Exit status 1 when any file has an error or a warning (infos and hints are
// advice, e.g. unused data), 0 otherwise.
// Usage: node gltf_validate.js VALIDATOR_DIR FILE.glb...
"use strict";
const fs = require("fs");
const path = require("path");

const [validatorDir, ...files] = process.argv.slice(2);
const validator = require(path.join(validatorDir, "node_modules", "gltf-validator"));

async function main() {
  let failed = false;
  for (const file of files) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      maxIssues: 100,
      // A .glb holds its buffer: an external resource would be a defect of ours.
      externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri} in a .glb`)),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} error(s), ${i.numWarnings} warning(s), ${i.numInfos} info(s), ` +
                `${i.numHints} hint(s)`);
    for (const m of i.messages)
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code}: ${m.message} (${m.pointer || ""})`);
    if (i.numErrors > 0 || i.numWarnings > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
}

main().catch((e) => {
  console.error(`gltf_validate.js: ${e.message}`);
  process.exit(2);
});
