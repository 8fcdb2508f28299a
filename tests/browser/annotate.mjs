// Drives headless Chromium through the annotation UI. Started by tests/service/browser.rs
// (mode "e2e") and by scripts/screenshots.sh (mode "screenshots"); parameters come as JSON in
// the first argument. Prints one JSON line of findings on success; on failure saves a
// screenshot and exits 1.
import { mkdirSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { check, openPage, tabTo } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { base, mode } = params;

async function waitSaved(page) {
  await page.waitForFunction(() => document.getElementById("save-status")?.textContent === "Saved");
}

async function slotLabels(page) {
  return page.$$eval(".slot", (slots) => slots.map((s) => s.getAttribute("aria-label")));
}

async function noHorizontalScroll(page) {
  return page.evaluate(() => document.documentElement.scrollWidth <= window.innerWidth);
}

// What the inspector shows and how large, by getBoundingClientRect.
async function inspectorSizes(page) {
  return page.evaluate(() => {
    const box = (sel) => document.querySelector(sel).getBoundingClientRect();
    const img = (sel) => document.querySelector(sel);
    return {
      focus_alt: img("#inspector figure.focus img").alt,
      before_alt: img("#inspector figure.before img").alt,
      focus_width: box("#inspector figure.focus img").width,
      focus_height: box("#inspector figure.focus img").height,
      before_width: box("#inspector figure.before img").width,
      focused_slot: document.activeElement?.dataset?.slot ?? null,
    };
  });
}

// The smallest rendered width of the page's thumbnails (candidate, slot and transition images).
async function thumbSizes(page) {
  return page.evaluate(() => {
    const widths = [...document.querySelectorAll(".card img, .slot-content img, li.transition .pair img, figure.current img")]
      .map((i) => i.getBoundingClientRect().width);
    return { min: Math.min(...widths), count: widths.length };
  });
}

async function acceptInvite(page, invite, password) {
  await page.goto(base + invite);
  await page.fill('input[name="password"]', password);
  await page.fill('input[name="repeat"]', password);
  await Promise.all([page.waitForURL(`${base}/annotate`), page.click('button[type="submit"]')]);
}

async function e2e(page) {
  const found = {};
  await acceptInvite(page, params.invite, "a long enough password");
  check((await page.textContent("body")).includes("0 of"), "queue page shows no progress");

  // Forward L = 3 by drag-and-drop.
  await Promise.all([page.waitForURL(`${base}/annotate/mini/${params.forward}`), page.click("#continue")]);
  check((await page.$$(".slot")).length === 2, "forward L=3 has two slots");
  check(await page.isVisible("figure.current img[alt$='(Current State)']"), "current state is shown");
  await page.dragAndDrop('.card[data-label="2"]', '.slot[data-slot="1"]');
  await waitSaved(page);
  // The inspector shows the slot's image large, beside the state before it.
  await page.hover('.slot[data-slot="1"]');
  found.forward_inspector = await inspectorSizes(page);
  check(found.forward_inspector.focus_alt === "Next State 2", `inspector shows ${found.forward_inspector.focus_alt}`);
  check(found.forward_inspector.before_alt === "Current State", `before is ${found.forward_inspector.before_alt}`);
  check(found.forward_inspector.focus_width >= 384 && found.forward_inspector.focus_height >= 384,
    `inspector image ${found.forward_inspector.focus_width}x${found.forward_inspector.focus_height} < 384`);
  found.forward_thumbs = await thumbSizes(page);
  check(found.forward_thumbs.min >= 140, `forward L=3 thumbnails ${found.forward_thumbs.min} px < 140`);
  check(await page.isDisabled("#submit"), "submit enabled with an empty slot");
  found.announced = await page.textContent("#announce");

  // Reload mid-item: the placement survives.
  await page.reload();
  const afterReload = await slotLabels(page);
  check(afterReload[0] === "Slot 1: Next State 2" && afterReload[1] === "Slot 2: empty",
    `partial answer lost on reload: ${afterReload}`);
  check(await page.$eval('.card[data-label="2"]', (c) => c.classList.contains("used")), "placed card not shown as used");
  found.after_reload = afterReload;

  // The lightbox enlarges an image.
  await page.click('.zoom[data-name="Next State 1"]');
  check(await page.isVisible("#lightbox img[alt='Next State 1']"), "lightbox did not open");
  await page.keyboard.press("Escape");

  await page.dragAndDrop('.card[data-label="1"]', '.slot[data-slot="2"]');
  await waitSaved(page);
  check(!(await page.isDisabled("#submit")), "submit still disabled with every slot filled");
  await Promise.all([page.waitForURL(`${base}/annotate/mini/${params.inverse}`), page.click("#submit")]);

  // Inverse L = 4 by keyboard only.
  check((await page.$$("li.transition")).length === 3, "inverse L=4 has three transitions");
  const press = async (label, key) => {
    await tabTo(page, `.card[data-label="${label}"]`);
    await page.keyboard.press(key);
  };
  await press(1, "3");
  await press(2, "1");
  await press(2, "3"); // onto a filled slot: swap with Action 1
  check((await slotLabels(page)).join("|") === "Slot 1: Action 1|Slot 2: empty|Slot 3: Action 2", "swap");
  await page.keyboard.press("Control+z");
  check((await slotLabels(page)).join("|") === "Slot 1: Action 2|Slot 2: empty|Slot 3: Action 1", "undo");
  await press(3, "1"); // Action 2 goes back to the library
  await press(3, "Backspace");
  await press(3, "1");
  await waitSaved(page);
  await page.reload();
  check((await slotLabels(page)).join("|") === "Slot 1: Action 3|Slot 2: empty|Slot 3: Action 1",
    `inverse partial answer lost on reload: ${await slotLabels(page)}`);
  await press(2, "2");
  await waitSaved(page);
  // Arrow keys walk the slots and the inspector follows focus: transition 2's two states.
  await tabTo(page, '.slot[data-slot="1"]');
  await page.keyboard.press("ArrowDown");
  found.inverse_inspector = await inspectorSizes(page);
  check(found.inverse_inspector.focused_slot === "2", `arrow moved focus to ${found.inverse_inspector.focused_slot}`);
  check(found.inverse_inspector.before_alt === "Next State 1" && found.inverse_inspector.focus_alt === "Next State 2",
    `inverse inspector shows ${found.inverse_inspector.before_alt} → ${found.inverse_inspector.focus_alt}`);
  check(found.inverse_inspector.before_width >= 384 && found.inverse_inspector.focus_width >= 384,
    "inverse inspector images below 384 px");
  found.announced_last = await page.textContent("#announce");
  await tabTo(page, "#submit");
  await Promise.all([page.waitForURL((url) => !url.pathname.endsWith(params.inverse)), page.keyboard.press("Enter")]);

  // L = 10 pages fit 1280 pixels, with thumbnails of at least 110 px.
  for (const item of params.wide || []) {
    await page.goto(`${base}/annotate/mini/${item}`);
    check(await noHorizontalScroll(page), `${item}: horizontal scrolling at 1280x800`);
    const thumbs = await thumbSizes(page);
    check(thumbs.min >= 110, `${item}: thumbnails ${thumbs.min} px < 110`);
  }
  found.wide_checked = (params.wide || []).length;

  // ENACT's real frames: thumbnails of at least 140 px up to L = 6 and 110 px at L = 10, the
  // inspector at 384 px or more, no sideways scrolling.
  found.sample = [];
  for (const { item, steps } of params.sample || []) {
    await page.goto(`${base}/annotate/sample/${item}`);
    await page.waitForLoadState("networkidle");
    check(await noHorizontalScroll(page), `sample ${item}: horizontal scrolling at 1280x800`);
    const thumbs = await thumbSizes(page);
    const least = steps <= 6 ? 140 : 110;
    check(thumbs.min >= least, `sample L=${steps}: thumbnails ${thumbs.min} px < ${least}`);
    await page.hover(".card >> nth=0");
    const inspector = await inspectorSizes(page);
    check(inspector.focus_width >= 384 && inspector.focus_height >= 384,
      `sample L=${steps}: inspector ${inspector.focus_width}x${inspector.focus_height}`);
    found.sample.push({ steps, thumb: thumbs.min, inspector: inspector.focus_width });
  }
  found.sample_checked = found.sample.length;
  return found;
}

// Screenshots of both pages at L = 3 and L = 10, with a few cards placed.
async function screenshots(page) {
  await acceptInvite(page, params.invite, "a long enough password");
  mkdirSync(params.out, { recursive: true });
  for (const shot of params.shots) {
    await page.goto(`${base}/annotate/${shot.dataset}/${shot.item}`);
    await page.waitForLoadState("networkidle");
    for (const [label, slot] of shot.place) {
      await page.click(`.card[data-label="${label}"]`);
      await page.click(`.slot[data-slot="${slot}"]`);
    }
    await page.waitForLoadState("networkidle");
    await page.evaluate(() => window.scrollTo(0, 0));
    check(await noHorizontalScroll(page), `${shot.item}: horizontal scrolling at 1280x800`);
    await page.screenshot({ path: join(params.out, shot.file) });
  }
  return { written: params.shots.length };
}

// Any console error (a refused script or style, a missing favicon, a script error) fails e2e.
const { context, page, consoleErrors } = await openPage(params);
try {
  const found = mode === "screenshots" ? await screenshots(page) : await e2e(page);
  check(consoleErrors.length === 0, `console errors:\n${consoleErrors.join("\n")}`);
  found.console_errors = consoleErrors.length;
  console.log(JSON.stringify({ ok: true, ...found }));
  await context.close();
} catch (error) {
  const shot = join(params.failure_dir || tmpdir(), "annotation-e2e-failure.png");
  await page.screenshot({ path: shot, fullPage: true }).catch(() => {});
  console.error(`browser test failed at ${page.url()}: ${error.stack}\nscreenshot: ${shot}`);
  await context.close().catch(() => {});
  process.exit(1);
}
