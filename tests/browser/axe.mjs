// axe-core (npm) run in Chromium over the annotator's and the public pages, in each locale
// asked for: prints one JSON line with every WCAG 2.x A/AA violation found (page, locale,
// rule, the elements). Started by tests/service/browser.rs, which fails on any. Each locale
// signs in through its own single-use invite, `params.invites[i]`; then, with `params.admin`
// ({name, password}), logs in as that admin for `params.admin_pages`.
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const require = createRequire(import.meta.url);
const axeSource = readFileSync(require.resolve("axe-core/axe.min.js"), "utf8");
const TAGS = ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa", "wcag22aa"];

const violations = [];
let checked = 0;
for (const [i, locale] of params.locales.entries()) {
  const { context, page } = await openPage({ ...params, locale });
  try {
    const invite = params.invites[i];
    await page.goto(params.base + invite);
    await report(page, locale, "/invite/…");
    await page.fill('input[name="password"]', "a long enough password");
    await page.fill('input[name="repeat"]', "a long enough password");
    await Promise.all([page.waitForURL(`${params.base}/annotate`), page.click('main button[type="submit"]')]);
    for (const path of params.pages) {
      await page.goto(params.base + path);
      await page.waitForLoadState("networkidle");
      await report(page, locale, path);
    }
    if (params.admin) {
      await page.goto(`${params.base}/login`);
      await page.fill('input[name="name"]', params.admin.name);
      await page.fill('input[name="password"]', params.admin.password);
      await Promise.all([page.waitForNavigation(), page.click('main button[type="submit"]')]);
      for (const path of params.admin_pages || []) {
        await page.goto(params.base + path);
        await page.waitForLoadState("networkidle");
        await report(page, locale, path);
      }
    }
  } finally {
    await context.close();
  }
}
console.log(JSON.stringify({ checked, violations }));

async function report(page, locale, path) {
  // Evaluated, not added as a <script>: the pages' CSP refuses inline scripts, as it should.
  await page.evaluate(`${axeSource}\n;true`);
  const result = await page.evaluate(
    (tags) => window.axe.run(document, { runOnly: { type: "tag", values: tags } }),
    TAGS,
  );
  checked += 1;
  for (const v of result.violations) {
    violations.push({
      locale,
      path,
      rule: v.id,
      impact: v.impact,
      help: v.help,
      nodes: v.nodes.slice(0, 5).map((n) => n.target.join(" ")),
    });
  }
}
