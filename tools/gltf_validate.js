#!/usr/bin/env node
// Validates glTF/GLB files with the Khronos glTF-Validator (npm package
// gltf-validator, which bootstrap.sh installs into tools/node); prints one
// JSON line per file: {"file", "errors", "warnings", "infos", "messages"}.
// Exit status 1 when a file has an error.
//   node tools/gltf_validate.js file.glb...
const fs = require('fs');
const path = require('path');
const validator = require(path.join(__dirname, 'node', 'node_modules', 'gltf-validator'));

async function main(files) {
  let bad = 0;
  for (const f of files) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    const i = report.issues;
    bad += i.numErrors > 0;
    console.log(JSON.stringify({file: f, errors: i.numErrors, warnings: i.numWarnings,
                                infos: i.numInfos,
                                messages: i.messages.slice(0, 5).map((m) => m.code + ': ' + m.message)}));
  }
  process.exit(bad ? 1 : 0);
}
main(process.argv.slice(2));
