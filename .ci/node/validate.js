// Validate glTF files with Khronos' glTF validator; print one JSON report per file, one per line.
// Usage: node validate.js FILE.glb|FILE.gltf ...   (external resources are read relative to each file)
"use strict";
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

async function report(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const dir = path.dirname(file);
  const result = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 200,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        const full = path.resolve(dir, decodeURIComponent(uri));
        fs.readFile(full, (err, data) => (err ? reject(err.toString()) : resolve(new Uint8Array(data))));
      }),
  });
  return { file, issues: result.issues };
}

(async () => {
  for (const file of process.argv.slice(2)) {
    try {
      process.stdout.write(JSON.stringify(await report(file)) + "\n");
    } catch (err) {
      process.stdout.write(JSON.stringify({ file, failure: String(err) }) + "\n");
    }
  }
})();
