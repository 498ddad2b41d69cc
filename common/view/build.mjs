// Bundles the two view pages (station/page, instructor/page) with the shared front-end
// (src/) and three.js into one folder: node build.mjs --out DIR
import * as esbuild from 'esbuild';
import { copyFileSync, mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, '../..');
const outIndex = process.argv.indexOf('--out');
if (outIndex < 0 || !process.argv[outIndex + 1]) {
  console.error('build.mjs: --out DIR required');
  process.exit(2);
}
const out = resolve(process.argv[outIndex + 1]);
mkdirSync(out, { recursive: true });
const pages = [
  { name: 'station', dir: join(root, 'station/page') },
  { name: 'console', dir: join(root, 'instructor/page') },
];
await esbuild.build({
  entryPoints: {
    ...Object.fromEntries(pages.map((p) => [p.name, join(p.dir, `${p.name}.ts`)])),
    frame_worker: join(here, 'src/frame_worker.ts'),
    audio_worklet: join(here, 'src/audio_worklet.ts'),
  },
  bundle: true,
  format: 'iife',
  target: 'es2020',
  minify: true,
  sourcemap: false,
  outdir: out,
  nodePaths: [join(here, 'node_modules')],
  logLevel: 'warning',
});
for (const p of pages) copyFileSync(join(p.dir, `${p.name}.html`), join(out, `${p.name}.html`));
