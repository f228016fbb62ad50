// node tests/gltf_validate.js VALIDATOR_DIR FILE... : the Khronos glTF
// validator (npm package gltf-validator, installed by `make gltf-validator`)
// over each file; prints one JSON object per line: the file, its error and
// warning counts and each issue code with how often it was reported.
const fs = require("fs");
const validator = require(process.argv[2]);

async function main() {
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)),
                                                 {maxIssues: 0, writeTimestamp: false});
    const codes = {};
    for (const m of report.issues.messages) codes[m.code] = (codes[m.code] || 0) + 1;
    console.log(JSON.stringify({file, errors: report.issues.numErrors, warnings: report.issues.numWarnings, codes}));
  }
}
main().catch((e) => {
  console.error(e);
  process.exit(1);
});
