// The pseudo-locale and right-to-left layout check: every page in `params.groups` is loaded in
// headless Chromium at each of `params.viewports`, with the `enact_lang` cookie set to
// `params.cookie` (the pseudo-locale: every message wrapped in ⟦…⟧, 40 % longer, `dir="rtl"`),
// and measured with getBoundingClientRect: the page must not scroll sideways, no element may
// reach outside the viewport (unless a scrolling or clipping box of its own holds it), no two
// texts may overlap, and every text of an SVG figure must lie inside its figure. Pages the
// server does not translate (the admin pages) are turned right-to-left here, so that their CSS
// is checked mirrored too.
//
// Groups are visited in order, each as who it names: "annotator" signs up through
// `params.invite` first, "admin" logs in with `params.admin` ({name, password}), "anyone" as
// whoever is signed in. Started by tests/service/browser.rs; parameters come as JSON in the first
// argument. Prints one JSON line: {checked: [...], consoleErrors}.
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { context, page, consoleErrors } = await openPage(params);
await context.addCookies([{ name: "enact_lang", value: params.cookie, url: params.base }]);

const checked = [];
try {
  for (const group of params.groups) {
    if (group.as === "annotator") {
      await page.goto(params.base + params.invite);
      await page.fill('input[name="password"]', params.password);
      await page.fill('input[name="repeat"]', params.password);
      await Promise.all([page.waitForURL(`${params.base}/annotate`), page.click('main button[type="submit"]')]);
    } else if (group.as === "admin") {
      await page.goto(`${params.base}/login`);
      await page.fill('input[name="name"]', params.admin.name);
      await page.fill('input[name="password"]', params.admin.password);
      await Promise.all([page.waitForNavigation(), page.click('main button[type="submit"]')]);
    }
    for (const [width, height] of params.viewports) {
      await page.setViewportSize({ width, height });
      for (const path of group.pages) {
        await page.goto(params.base + path);
        await page.waitForLoadState("networkidle");
        const found = await page.evaluate(measure, group.translated);
        const result = { path, viewport: `${width}x${height}`, ...found };
        checked.push(result);
        if (found.problems.length && params.failure_dir) {
          const name = `${width}-${path.replace(/[^a-z0-9]+/gi, "_")}.png`;
          await page.screenshot({ path: `${params.failure_dir}/layout-${name}`, fullPage: true });
        }
      }
    }
  }
  console.log(JSON.stringify({ checked, consoleErrors }));
  await context.close();
} catch (error) {
  console.error(`layout check failed at ${page.url()}: ${error.stack}`);
  await context.close().catch(() => {});
  process.exit(1);
}

/// Runs in the page: what overflows or overlaps. `translated` says whether the server renders
/// this page in the pseudo-locale; when it does not, the page is turned right-to-left here.
function measure(translated) {
  const html = document.documentElement;
  const served = { dir: html.getAttribute("dir"), lang: html.getAttribute("lang") };
  if (!translated) html.setAttribute("dir", "rtl");
  const viewport = html.clientWidth;
  const problems = [];
  const describe = (el) => {
    const classes = typeof el.className === "string" && el.className ? `.${el.className.trim().split(/\s+/).join(".")}` : "";
    const text = (el.textContent || "").trim().replace(/\s+/g, " ").slice(0, 60);
    return `<${el.tagName.toLowerCase()}${el.id ? `#${el.id}` : ""}${classes}> "${text}"`;
  };
  // The nearest ancestor that clips or scrolls what overflows it sideways (an SVG clips its
  // drawing too): what it holds is checked against it, and it is checked against the page.
  const clipper = (el) => {
    for (let a = el.parentElement; a && a !== document.body; a = a.parentElement) {
      if (a instanceof SVGSVGElement || getComputedStyle(a).overflowX !== "visible") return a;
    }
    return null;
  };
  // Not drawn (a closed <details>, display: none), or drawn for screen readers only.
  const hidden = (el) =>
    !el.checkVisibility({ contentVisibilityAuto: true, visibilityProperty: true }) ||
    el.closest(".sr-only, .visually-hidden, title, option");

  if (html.scrollWidth > viewport + 1) {
    // Whatever is wider than the box that holds it without scrolling, innermost first.
    const wide = [...document.body.querySelectorAll("*")]
      .filter((el) => !hidden(el) && el.scrollWidth > el.clientWidth + 1 && getComputedStyle(el).overflowX === "visible")
      .reverse()
      .slice(0, 3)
      .map((el) => `${describe(el)} (${el.scrollWidth} px in ${el.clientWidth})`);
    problems.push(`the page scrolls sideways: ${html.scrollWidth} px wide in a ${viewport} px viewport; ${wide.join("; ")}`);
  }
  for (const el of document.body.querySelectorAll("*")) {
    const r = el.getBoundingClientRect();
    if (r.width === 0 || r.height === 0 || hidden(el) || clipper(el)) continue;
    if (r.left < -0.5 || r.right > viewport + 0.5) {
      problems.push(`outside the viewport (${Math.round(r.left)}–${Math.round(r.right)} of ${viewport} px): ${describe(el)}`);
    }
  }

  // Every visible text's boxes: one per line of HTML text; the element's box for SVG text.
  const texts = [];
  const seenSvg = new Set();
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  for (let node = walker.nextNode(); node; node = walker.nextNode()) {
    const el = node.parentElement;
    if (!el || !node.data.trim() || hidden(el)) continue;
    let rects;
    if (el instanceof SVGElement) {
      const text = el.closest("text");
      if (!text || seenSvg.has(text)) continue;
      seenSvg.add(text);
      const r = text.getBoundingClientRect();
      const box = text.ownerSVGElement.getBoundingClientRect();
      if (r.left < box.left - 0.5 || r.right > box.right + 0.5 || r.top < box.top - 0.5 || r.bottom > box.bottom + 0.5) {
        const at = (b) => `${Math.round(b.left)}–${Math.round(b.right)}`;
        problems.push(`a figure's text is cut by its figure (${at(r)} in ${at(box)}): ${describe(text)}`);
      }
      rects = [r];
    } else {
      const range = document.createRange();
      range.selectNodeContents(node);
      rects = [...range.getClientRects()];
    }
    // Only what its scrolling box shows of it.
    const holder = clipper(el);
    const bound = holder && !(holder instanceof SVGSVGElement) ? holder.getBoundingClientRect() : null;
    for (const r of rects) {
      const box = bound
        ? { left: Math.max(r.left, bound.left), right: Math.min(r.right, bound.right), top: Math.max(r.top, bound.top), bottom: Math.min(r.bottom, bound.bottom) }
        : { left: r.left, right: r.right, top: r.top, bottom: r.bottom };
      if (box.right - box.left > 0.5 && box.bottom - box.top > 0.5) texts.push({ node, el, ...box });
    }
  }
  // Two texts overlap when they share more than 2 px each way (glyph boxes of neighbouring
  // lines may touch).
  texts.sort((a, b) => a.top - b.top);
  const reported = new Set();
  for (let i = 0; i < texts.length; i++) {
    const a = texts[i];
    for (let j = i + 1; j < texts.length && texts[j].top < a.bottom - 2; j++) {
      const b = texts[j];
      if (a.node === b.node) continue;
      const across = Math.min(a.right, b.right) - Math.max(a.left, b.left);
      const down = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
      const key = `${describe(a.el)} | ${describe(b.el)}`;
      if (across > 2 && down > 2 && !reported.has(key)) {
        reported.add(key);
        problems.push(`texts overlap: ${key}`);
      }
    }
  }

  // Text that did not come through the catalogue: English words outside ⟦…⟧ (diagnostics for
  // the reader of a failure; data such as item ids and action texts is expected here).
  const untranslated = new Set();
  let pseudo = 0;
  for (const t of texts) {
    const data = t.node.data.trim();
    if (data.includes("⟦") || data.includes("⟧")) pseudo += 1;
    else if (/[A-Za-z]{3,}/.test(data) && untranslated.size < 40) untranslated.add(data.slice(0, 80));
  }
  return { ...served, problems, pseudo, untranslated: [...untranslated] };
}
