// Loads a study report page in headless Chromium at 1280x800 and measures its figures: every
// text of the heatmap and of the handedness panel must lie inside its SVG's box, and no two
// texts on one line of the heatmap may overlap (a label cut or run into its neighbour fails).
// Started by tests/service/browser.rs; parameters come as JSON in the first argument. Prints
// one JSON line.
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { context, page, consoleErrors } = await openPage(params);
try {
  await page.goto(params.url, { waitUntil: "load" });
  const found = await page.evaluate(() => {
    const measure = (selector) => {
      const svg = document.querySelector(selector);
      if (!svg) return null;
      const box = svg.getBoundingClientRect();
      const texts = [...svg.querySelectorAll("text")].map((t) => {
        const r = t.getBoundingClientRect();
        return { text: t.textContent, left: r.left, right: r.right, top: r.top, bottom: r.bottom };
      });
      const outside = texts
        .filter((t) => t.left < box.left - 0.5 || t.right > box.right + 0.5 || t.top < box.top - 0.5 || t.bottom > box.bottom + 0.5)
        .map((t) => t.text);
      // Texts on one line (same vertical middle) must not overlap.
      const overlapping = [];
      for (let i = 0; i < texts.length; i++) {
        for (let j = i + 1; j < texts.length; j++) {
          const a = texts[i], b = texts[j];
          const sameLine = Math.abs((a.top + a.bottom) / 2 - (b.top + b.bottom) / 2) < 2;
          if (sameLine && a.left < b.right - 0.5 && b.left < a.right - 0.5) overlapping.push(`${a.text} | ${b.text}`);
        }
      }
      return { texts: texts.length, outside, overlapping, width: box.width, height: box.height };
    };
    return {
      heatmap: measure("svg.study-heatmap"),
      handedness: measure("svg.study-handedness"),
      panels: document.querySelectorAll("svg.study-heatmap g.panel").length,
      cell_rows: document.querySelectorAll("table.study-cells tbody tr").length,
    };
  });
  if (params.shot) await page.screenshot({ path: params.shot, fullPage: true });
  if (consoleErrors.length) throw new Error(`console errors:\n${consoleErrors.join("\n")}`);
  console.log(JSON.stringify({ ok: true, ...found }));
  await context.close();
} catch (error) {
  console.error(`study page failed at ${page.url()}: ${error.stack}`);
  await context.close().catch(() => {});
  process.exit(1);
}
