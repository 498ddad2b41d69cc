// Debian's Chromium, headless with software WebGL, for the apps' own pictures
// (microdex-station --screenshot: station/page/screenshot.mjs; microdex-replay --render:
// instructor/page/render.mjs). The tests have their own launcher (tests/web/browser.mjs).
//   const { page, close } = await openHeadless({ width, height });
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const { chromium } = createRequire(join(here, 'package.json'))('playwright-core');

// A fresh profile in a temporary folder, removed by close(); MICRODEX_CHROMIUM overrides the
// browser's path.
export async function openHeadless({ width = 1280, height = 720 } = {}) {
  const profile = mkdtempSync(join(tmpdir(), 'microdex-headless-'));
  let context;
  try {
    context = await chromium.launchPersistentContext(profile, {
      executablePath: process.env.MICRODEX_CHROMIUM || '/usr/bin/chromium',
      headless: true,
      viewport: { width, height },
      args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
             '--disable-background-networking', '--disable-component-update', '--disable-sync',
             '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
    });
    const page = await context.newPage();
    const close = async () => {
      await context.close().catch(() => undefined);
      rmSync(profile, { recursive: true, force: true });
    };
    return { page, close };
  } catch (e) {
    await context?.close().catch(() => undefined);
    rmSync(profile, { recursive: true, force: true });
    throw e;
  }
}
