// The Chromium every browser test drives: headless, a fresh profile, 1280x800, and the console
// errors and page errors of whatever it loads (a refused script or style, a missing file, a
// script error) collected for the test to fail on.
import { chromium } from "playwright-core";
import { mkdtempSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";

const FLAGS = [
  "--headless",
  "--no-sandbox",
  "--disable-gpu",
  "--disable-dev-shm-usage",
  "--no-first-run",
  "--disable-background-networking",
  "--disable-component-update",
  "--disable-sync",
];

/// Launches Chromium (`params.chromium`, else /usr/bin/chromium) and opens one page; with
/// `params.locale` the browser asks for that language (Accept-Language, navigator.language).
export async function openPage(params, timeout = 15000) {
  const userDataDir = mkdtempSync(join(tmpdir(), "enact-hub-chromium-"));
  const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath: params.chromium || "/usr/bin/chromium",
    headless: true,
    args: FLAGS,
    viewport: { width: 1280, height: 800 },
    ...(params.locale ? { locale: params.locale } : {}),
  });
  const page = context.pages()[0] || (await context.newPage());
  page.setDefaultTimeout(timeout);
  const consoleErrors = [];
  page.on("console", (m) => m.type() === "error" && consoleErrors.push(`${page.url()}: ${m.text()}`));
  page.on("pageerror", (e) => consoleErrors.push(`${page.url()}: ${e.message}`));
  return { context, page, consoleErrors };
}

/// Throws `message` unless `condition` holds.
export function check(condition, message) {
  if (!condition) throw new Error(message);
}

/// Presses Tab until the focused element matches `selector`: keyboard only, no clicks.
export async function tabTo(page, selector, presses = 300) {
  for (let i = 0; i < presses; i++) {
    if (await page.evaluate((s) => document.activeElement?.matches(s) ?? false, selector)) return;
    await page.keyboard.press("Tab");
  }
  throw new Error(`Tab never reached ${selector}`);
}
