// Bundles the front-end's unit tests (unit/*.test.ts, with the modules of common/view/src and
// three.js) with esbuild, then runs them with node's test runner.
// node run_unit.mjs --out DIR
import { spawnSync } from 'node:child_process';
import { readdirSync, mkdirSync } from 'node:fs';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { sourceDir } from './browser.mjs';
import { args } from './harness.mjs';

const a = args({ out: join(sourceDir, 'build/web-unit') });
mkdirSync(a.out, { recursive: true });
const require = createRequire(join(sourceDir, 'common/view/package.json'));
const esbuild = require('esbuild');
const unitDir = join(sourceDir, 'tests/web/unit');
const tests = readdirSync(unitDir).filter((f) => f.endsWith('.test.ts'));
await esbuild.build({
  entryPoints: tests.map((t) => join(unitDir, t)),
  bundle: true,
  platform: 'node',
  format: 'esm',
  outdir: a.out,
  outExtension: { '.js': '.mjs' },
  nodePaths: [join(sourceDir, 'common/view/node_modules')],
  external: ['node:*'],
  logLevel: 'warning',
});
const files = tests.map((t) => join(a.out, t.replace(/\.ts$/, '.mjs')));
const r = spawnSync(process.execPath, ['--test', ...files], { stdio: 'inherit' });
process.exit(r.status ?? 1);
