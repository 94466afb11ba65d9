// Validates .glb files with the Khronos glTF validator (npm gltf-validator,
// installed by tools/install-deps.sh under build/node_modules). Prints the
// report's counts and exits 1 when any file has errors (or warnings when
// --strict is given).
import { createRequire } from 'module';
import { readFileSync } from 'fs';
import path from 'path';

const args = process.argv.slice(2);
const strict = args.includes('--strict');
const files = args.filter((a) => a !== '--strict');
const modules = process.env.TSR_NODE_MODULES;
const require = createRequire(path.join(modules, 'x.js'));
const validator = require('gltf-validator');

let failed = false;
for (const f of files) {
  const bytes = new Uint8Array(readFileSync(f));
  const report = await validator.validateBytes(bytes, { uri: f, maxIssues: 20 });
  const n = report.issues;
  console.log(`${f}: ${n.numErrors} errors, ${n.numWarnings} warnings, ${n.numInfos} infos`);
  for (const m of n.messages) console.log(`  ${m.severity === 0 ? 'error' : 'note'} ${m.code}: ${m.message} (${m.pointer || ''})`);
  if (n.numErrors > 0 || (strict && n.numWarnings > 0)) failed = true;
}
process.exit(failed ? 1 : 0);
