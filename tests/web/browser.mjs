// Headless Chromium for the web tests and the measurement script: Debian's chromium through
// playwright-core (no browser download), software WebGL (SwiftShader), loopback only.
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
export const sourceDir = resolve(here, '../..');
const require = createRequire(join(sourceDir, 'common/view/package.json'));
const { chromium } = require('playwright-core');

export const CHROMIUM = process.env.MICRODEX_CHROMIUM || '/usr/bin/chromium';

// A fresh profile each time; returns the context (newPage) and close(). ignoreHTTPSErrors: for
// a console whose certificate comes from a course CA the browser does not know. extraArgs:
// more Chromium switches (e.g. --autoplay-policy=no-user-gesture-required).
export async function launchBrowser({ width = 1280, height = 720, ignoreHTTPSErrors = false,
                                      extraArgs = [] } = {}) {
  if (!existsSync(CHROMIUM)) {
    throw new Error(`${CHROMIUM} not found: deploy/install-deps installs Debian's chromium`);
  }
  const profile = mkdtempSync(join(tmpdir(), 'microdex-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    viewport: { width, height },
    ignoreHTTPSErrors,
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--disable-background-timer-throttling', '--disable-renderer-backgrounding',
      '--disable-backgrounding-occluded-windows', ...extraArgs,
    ],
  });
  const close = async () => {
    await context.close().catch(() => undefined);
    rmSync(profile, { recursive: true, force: true });
  };
  return { context, close };
}
