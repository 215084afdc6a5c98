// Runs the Khronos glTF validator (npm package gltf-validator) on one file and prints a JSON
// summary: {"errors":N,"warnings":N,"infos":N,"messages":[...errors and warnings...]}.
// Usage: node tools/gltf-validate.js FILE.glb|FILE.gltf   (GLTF_VALIDATOR_DIR: folder holding node_modules)
const fs = require('fs');
const path = require('path');
const dir = process.env.GLTF_VALIDATOR_DIR || path.join(__dirname, '..', '.ci', 'gltf-validator');
const validator = require(path.join(dir, 'node_modules', 'gltf-validator'));
const file = process.argv[2];
validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: file,
    maxIssues: 200,
    // A .gltf names its .bin beside it.
    externalResourceFunction: (uri) =>
      Promise.resolve(
        new Uint8Array(fs.readFileSync(path.join(path.dirname(file), decodeURIComponent(uri)))),
      ),
  })
  .then((r) => {
    const messages = r.issues.messages.filter((m) => m.severity <= 1);
    console.log(JSON.stringify({
      errors: r.issues.numErrors,
      warnings: r.issues.numWarnings,
      infos: r.issues.numInfos,
      messages,
    }));
  })
  .catch((e) => {
    console.error(String(e));
    process.exit(2);
  });
