// Loads a crowded leaderboard page in headless Chromium at 1280x800 and reports what a reader
// gets: table rows, lines per chart panel, page width, load time. Started by
// tests/service/browser.rs; parameters come as JSON in the first argument. Prints one JSON line.
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
// Any console error (a refused script or style, a missing file, a script error) fails the run.
const { context, page, consoleErrors } = await openPage(params);
try {
  const started = Date.now();
  await page.goto(params.url, { waitUntil: "load" });
  const load_ms = Date.now() - started;
  const found = await page.evaluate(() => ({
    table_rows: document.querySelectorAll("table.leaderboard tbody tr").length,
    lines_per_panel: [...document.querySelectorAll("figure.chart svg > g")].map(
      (g) => g.querySelectorAll("polyline").length,
    ),
    legend: document.querySelectorAll("figure.chart figcaption .legend-entry").length,
    scroll_width: document.documentElement.scrollWidth,
    client_width: document.documentElement.clientWidth,
    html_bytes: document.documentElement.outerHTML.length,
  }));
  if (params.shot) await page.screenshot({ path: params.shot });
  // The other public pages of the board: error analyses, the home page, the API docs.
  for (const path of params.also || []) {
    await page.goto(new URL(path, params.url).href, { waitUntil: "load" });
  }
  if (consoleErrors.length) throw new Error(`console errors:\n${consoleErrors.join("\n")}`);
  found.pages_without_console_errors = 1 + (params.also || []).length;
  console.log(JSON.stringify({ ok: true, load_ms, ...found }));
  await context.close();
} catch (error) {
  console.error(`leaderboard page failed at ${page.url()}: ${error.stack}`);
  await context.close().catch(() => {});
  process.exit(1);
}
