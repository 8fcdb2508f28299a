// Drives headless Chromium through a curator's episode: upload the frames, mark key frames,
// draw the first scene graph and edit the next ones by keyboard and by mouse, watching the
// transition's sentences update, then save; axe-core then checks the episode pages. Started
// by tests/service/episode_browser.rs (and through it by scripts/screenshots-episode.sh, which
// asks for the README's pictures). Parameters come as JSON in the first argument; prints one
// JSON line of findings, or saves a screenshot and exits 1.
import { createRequire } from "node:module";
import { mkdirSync, readFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { check, openPage, tabTo } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { base } = params;

async function login(page) {
  await page.goto(base + params.invite);
  await page.fill('input[name="password"]', "a long enough password");
  await page.fill('input[name="repeat"]', "a long enough password");
  await Promise.all([page.waitForURL(`${base}/annotate`), page.click('main button[type="submit"]')]);
}

// The sentences and components shown for the key frame on screen, once the server has
// described the latest change (the draft status is written after the description).
async function transition(page) {
  await page.waitForFunction(() => document.getElementById("save-status")?.textContent === "Draft saved.");
  return page.evaluate(() => ({
    sentences: [...document.querySelectorAll("#sentences li:not(.meta)")].map((li) => li.textContent),
    components: [...document.querySelectorAll("#signatures li")].map((li) => li.textContent),
    problems: [...document.querySelectorAll("#problems p")].map((p) => p.textContent),
  }));
}

// Marks the next edit as pending, so `transition` waits for its description.
async function edit(page, action) {
  await page.evaluate(() => { document.getElementById("save-status").textContent = ""; });
  await action();
}

// Keyboard: focus the filmstrip on the frame shown and press keys.
async function stripKeys(page, keys) {
  await page.focus(".strip-frame.current");
  for (const key of keys) await page.keyboard.press(key);
}

// Keyboard only: Tab to the add-object form, type, Enter.
async function addObjectByKeyboard(page, name, category) {
  await tabTo(page, '#add-node input[name="name"]');
  await page.keyboard.type(name);
  await page.keyboard.press("Tab");
  await page.keyboard.type(category);
  await page.keyboard.press("Enter");
}

// Keyboard only: the relation form's selects take typed names, then Enter adds it.
async function addRelationByKeyboard(page, from, state, to) {
  await tabTo(page, '#add-edge select[name="from"]');
  await page.selectOption('#add-edge select[name="from"]', from);
  await page.keyboard.press("Tab");
  await page.selectOption('#add-edge select[name="state"]', state);
  await page.keyboard.press("Tab");
  await page.selectOption('#add-edge select[name="to"]', to);
  await page.keyboard.press("Tab");
  await page.keyboard.press("Enter");
}

const stateBox = (name, state) => `.node-row[data-name="${name}"] .state-box[data-state="${state}"]`;
const removeEdge = (text) => `.edge-row[data-edge="${text}"] .remove-edge`;

async function upload(page) {
  await page.goto(`${base}/admin/episodes/new`);
  await page.fill('#upload input[name="name"]', params.episode);
  await page.fill('#upload input[name="scene"]', "kitchen");
  await page.setInputFiles('#upload input[name="frames"]', params.frames);
  await Promise.all([
    page.waitForURL(`${base}/episodes/${params.episode}`),
    page.click('#upload button[type="submit"]'),
  ]);
}

async function e2e(page) {
  const found = { transitions: [] };
  await login(page);
  await upload(page);
  check((await page.$$(".strip-frame")).length === 12, "the filmstrip shows 12 frames");

  // Key frames 1, 3 and 6 by keyboard; 9 and 12 by mouse (click the frame, then the button).
  await stripKeys(page, ["Space", "ArrowRight", "ArrowRight", "Space", "ArrowRight", "ArrowRight", "ArrowRight", "Space"]);
  await page.click('.strip-frame[data-position="8"]');
  await page.click("#toggle-key");
  await page.click('.strip-frame[data-position="11"]');
  await page.click("#toggle-key");
  found.key_summary = await page.textContent("#key-summary");
  check(found.key_summary.includes("5 key frames") && found.key_summary.includes("3, 4"),
    `key frame summary: ${found.key_summary}`);

  // Back to the first key frame (Home) and build its graph from scratch by keyboard.
  await stripKeys(page, ["Home"]);
  for (const [name, category] of params.objects) await addObjectByKeyboard(page, name, category);
  await addRelationByKeyboard(page, "apple_1", "OnTop", "table_1");
  await addRelationByKeyboard(page, "fridge_1", "NextTo", "table_1");
  await transition(page);
  check((await page.$$(".node-row")).length === params.objects.length, "objects added by keyboard");
  await shoot(page, "episode-editor-first.png");

  // Key frame 2 (PageDown) starts as a copy of key frame 1: edit only what changed.
  await stripKeys(page, ["PageDown"]);
  check((await page.$$(".node-row")).length === params.objects.length, "key frame 2 starts as a copy");
  found.unchanged = (await transition(page)).problems;
  await edit(page, () => addRelationByKeyboard(page, "robot_r1", "LeftGrasping", "apple_1"));
  await edit(page, async () => {
    await tabTo(page, removeEdge("apple_1 OnTop table_1"));
    await page.keyboard.press("Enter");
  });
  found.transitions.push(await transition(page));

  // Key frame 3 by mouse: open the fridge.
  await page.click('.strip-frame[data-position="5"]');
  await edit(page, () => page.click(stateBox("fridge_1", "Open")));
  found.transitions.push(await transition(page));

  // Key frame 4, mouse: the apple goes inside the fridge; an edge to a missing object is
  // flagged before saving, then set right.
  await page.click('.strip-frame[data-position="8"]');
  await edit(page, async () => {
    await page.selectOption('#add-edge select[name="from"]', "apple_1");
    await page.selectOption('#add-edge select[name="state"]', "Inside");
    await page.selectOption('#add-edge select[name="to"]', "fridge_1");
    await page.click('#add-edge button[type="submit"]');
  });
  await edit(page, () => page.click('.node-row[data-name="table_1"] .remove-node'));
  await edit(page, () => page.click(removeEdge("robot_r1 LeftGrasping apple_1")));
  const dangling = await transition(page);
  found.dangling = dangling.problems;
  await edit(page, async () => {
    await page.fill('#add-node input[name="name"]', "table_1");
    await page.fill('#add-node input[name="category"]', "table");
    await page.click('#add-node button[type="submit"]');
  });
  found.transitions.push(await transition(page));
  await shoot(page, "episode-editor-transition.png");

  // Key frame 5 by keyboard: close the fridge (Tab to its Open box, Space).
  await stripKeys(page, ["PageDown"]);
  await edit(page, async () => {
    await tabTo(page, stateBox("fridge_1", "Open"));
    await page.keyboard.press("Space");
  });
  found.transitions.push(await transition(page));

  await page.click("#save");
  await page.waitForFunction(() => document.getElementById("save-status")?.textContent === "Saved.");

  // A reload shows the saved graphs and their sentences again.
  await page.reload();
  await stripKeys(page, ["End"]);
  found.after_reload = await transition(page);

  if (params.axe) found.axe = await axe(page, params.axe);
  return found;
}

// axe-core over `paths`: every WCAG 2.x A/AA violation, by page.
async function axe(page, paths) {
  const require = createRequire(import.meta.url);
  const source = readFileSync(require.resolve("axe-core/axe.min.js"), "utf8");
  const violations = [];
  for (const path of paths) {
    await page.goto(base + path);
    await page.waitForLoadState("networkidle");
    // Evaluated, not added as a <script>: the pages' CSP refuses inline scripts.
    await page.evaluate(`${source}\n;true`);
    const result = await page.evaluate(() => window.axe.run(document, {
      runOnly: { type: "tag", values: ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa", "wcag22aa"] },
    }));
    for (const v of result.violations) {
      violations.push({ path, rule: v.id, nodes: v.nodes.map((n) => n.target.join(" ")) });
    }
  }
  return violations;
}

// With `params.screenshots` (a folder), the README's pictures of the editor at this point.
async function shoot(page, file) {
  if (!params.screenshots) return;
  mkdirSync(params.screenshots, { recursive: true });
  // The filmstrip at the top of the window, the editor and the transition below it.
  await page.evaluate(() => document.getElementById("filmstrip").scrollIntoView());
  await page.screenshot({ path: join(params.screenshots, file) });
}

const { context, page, consoleErrors } = await openPage(params);
try {
  const found = await e2e(page);
  check(consoleErrors.length === 0, `console errors:\n${consoleErrors.join("\n")}`);
  found.console_errors = consoleErrors.length;
  console.log(JSON.stringify({ ok: true, ...found }));
  await context.close();
} catch (error) {
  const shot = join(params.failure_dir || tmpdir(), "episode-e2e-failure.png");
  await page.screenshot({ path: shot, fullPage: true }).catch(() => {});
  console.error(`episode browser test failed at ${page.url()}: ${error.stack}\nscreenshot: ${shot}`);
  await context.close().catch(() => {});
  process.exit(1);
}
