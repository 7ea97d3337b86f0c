// Validate glTF/GLB files with the Khronos glTF-Validator.
// Usage: node validate.mjs FILE... ; prints one JSON line per file:
//   {"file":..., "errors":N, "warnings":N, "infos":N, "hints":N, "messages":[{code,severity,pointer,message}]}
// Exit code 0 when every file has 0 errors and 0 warnings, 1 otherwise, 2 on a crash.
import fs from "node:fs";
import path from "node:path";
import validator from "gltf-validator";

let bad = 0;
for (const file of process.argv.slice(2)) {
  const full = path.resolve(file);
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(full)), {
    uri: path.basename(full),
    maxIssues: 1000,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(full), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const i = report.issues;
  const names = ["error", "warning", "info", "hint"];
  const out = {
    file,
    errors: i.numErrors,
    warnings: i.numWarnings,
    infos: i.numInfos,
    hints: i.numHints,
    messages: i.messages.map((m) => ({ code: m.code, severity: names[m.severity], pointer: m.pointer, message: m.message })),
  };
  if (i.numErrors + i.numWarnings > 0) bad = 1;
  console.log(JSON.stringify(out));
}
// exitCode, not exit(): exit() can cut off stdout still being written to a pipe.
process.exitCode = bad;
