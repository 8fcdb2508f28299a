// Opens two assigned items in headless Chromium, a gold item and an ordinary one of the same
// kind, after annotate.js has built their boards, and prints each page's normalised DOM: every
// element's depth, tag and attributes in document order, with the item's own id replaced by
// ITEM and the values that carry the item's content (image sources, texts, labels) dropped.
// Started by tests/service/browser.rs; parameters come as JSON in the first argument. Prints
// one JSON line.
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { base, invite, items } = params;
const { context, page, consoleErrors } = await openPage(params);
try {
  await page.goto(base + invite);
  await page.fill('input[name="password"]', "a long enough password");
  await page.fill('input[name="repeat"]', "a long enough password");
  await Promise.all([page.waitForURL(`${base}/annotate`), page.click('button[type="submit"]')]);
  const shapes = [];
  for (const item of items) {
    await page.goto(`${base}/annotate/mini/${item}`, { waitUntil: "networkidle" });
    shapes.push(
      await page.evaluate((item) => {
        // Attributes whose values are the item's content, not its markup.
        const content = new Set(["src", "srcset", "href", "alt", "title", "aria-label", "value", "action", "data-src"]);
        const out = [];
        const walk = (el, depth) => {
          const attrs = [...el.attributes]
            .map((a) => `${a.name}=${content.has(a.name) ? "" : a.value.split(item).join("ITEM")}`)
            .sort();
          out.push(`${depth} ${el.tagName.toLowerCase()} [${attrs.join(" ")}]`);
          for (const child of el.children) walk(child, depth + 1);
        };
        walk(document.documentElement, 0);
        return out;
      }, item),
    );
  }
  console.log(JSON.stringify({ shapes, console_errors: consoleErrors.length, errors: consoleErrors }));
} finally {
  await context.close();
}
