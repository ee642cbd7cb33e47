// validate_gltf.mjs - runs the Khronos glTF-Validator (npm gltf-validator) on .glb files.
//
// usage: node validate_gltf.mjs FILE.glb [EXPECTED_FRAMES]
// Prints the validator's counts and every issue; exits 1 when the report has an error (or a
// warning: sem's files should have none), or when EXPECTED_FRAMES is given and the file does
// not hold one animation whose time input has that many keys, or when the validator is not
// installed (gltf_validator_test.sh skips the test when node or npm is missing).
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, 'package.json'));
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error(`gltf-validator is not installed in ${here}/node_modules: run scripts/test.sh ` +
                `(or: npm ci --prefix ${here})`);
  process.exit(1);
}

const [file, expectedFrames] = process.argv.slice(2);
if (!file) {
  console.error('usage: node validate_gltf.mjs FILE.glb [EXPECTED_FRAMES]');
  process.exit(2);
}
const bytes = new Uint8Array(readFileSync(file));
const report = await validator.validateBytes(bytes, { uri: file, maxIssues: 0 });
const i = report.issues;
console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ` +
            `${i.numHints} hints; ${report.info.animationCount} animations, ${report.info.drawCallCount} draw calls, ` +
            `${report.info.materialCount} materials, ${report.info.totalVertexCount} vertices`);
for (const m of i.messages) console.log(`  ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code}: ${m.message} (${m.pointer || ''})`);
let failed = i.numErrors > 0 || i.numWarnings > 0;
if (expectedFrames !== undefined) {
  // the glb's JSON chunk: one animation, its sampler's input accessor has one key per frame
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const jsonLength = view.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + jsonLength)));
  const animations = json.animations || [];
  const keys = animations.length === 1 ? json.accessors[animations[0].samplers[0].input].count : 0;
  if (keys !== Number(expectedFrames)) {
    console.log(`expected one animation with ${expectedFrames} keys, found ${animations.length} animations, ${keys} keys`);
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
