// The first ten minutes: follows the login link `serve --demo` printed, annotates one forward
// item with the mouse and one inverse item with the keyboard, then reads the Human row on the
// demo's leaderboard. Started by tests/service/browser.rs; parameters come as JSON in the first
// argument. Prints one JSON line of findings; on failure saves a screenshot and exits 1.
import { tmpdir } from "node:os";
import { join } from "node:path";
import { check, openPage, tabTo } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const base = new URL(params.link).origin;

async function waitSaved(page) {
  await page.waitForFunction(() => document.getElementById("save-status")?.textContent === "Saved");
}

const { context, page, consoleErrors } = await openPage(params, 20000);
try {
  const found = { done: [] };
  await page.goto(params.link);
  check(new URL(page.url()).pathname === "/annotate", `the link led to ${page.url()}`);
  await Promise.all([page.waitForURL(/\/annotate\/demo\//), page.click("#continue")]);
  for (let n = 0; n < 6 && found.done.length < 2; n++) {
    const forward = await page.$eval("#annotator", (a) => a.classList.contains("forward"));
    const labels = await page.$$eval(".card", (cs) => cs.map((c) => Number(c.dataset.label)));
    const wanted = forward ? "forward" : "inverse";
    if (found.done.includes(wanted)) {
      // Already done this direction: skip ahead through the queue.
      await page.goto(`${base}/annotate/next`);
      continue;
    }
    if (forward) {
      // With the mouse: drag each candidate onto a slot.
      for (const [i, label] of labels.entries()) {
        await page.dragAndDrop(`.card[data-label="${label}"]`, `.slot[data-slot="${i + 1}"]`);
      }
      await waitSaved(page);
      const at = page.url();
      await Promise.all([page.waitForURL((u) => u.href !== at), page.click("#submit")]);
    } else {
      // With the keyboard alone: focus each action card and press its slot number.
      for (const [i, label] of labels.entries()) {
        await tabTo(page, `.card[data-label="${label}"]`);
        await page.keyboard.press(String(i + 1));
      }
      await waitSaved(page);
      await tabTo(page, "#submit");
      const at = page.url();
      await Promise.all([page.waitForURL((u) => u.href !== at), page.keyboard.press("Enter")]);
    }
    found.done.push(wanted);
  }
  check(found.done.length === 2, `annotated ${found.done}`);
  await page.goto(`${base}/leaderboard/demo`);
  found.human_row = await page.$$eval("table.leaderboard tbody tr", (rows) =>
    rows.map((r) => r.textContent.replace(/\s+/g, " ").trim()).find((t) => t.includes("Human")) ?? null);
  check(consoleErrors.length === 0, `console errors:\n${consoleErrors.join("\n")}`);
  found.console_errors = 0;
  console.log(JSON.stringify({ ok: true, ...found }));
  await context.close();
} catch (error) {
  const shot = join(params.failure_dir || tmpdir(), "demo-link-failure.png");
  await page.screenshot({ path: shot, fullPage: true }).catch(() => {});
  console.error(`demo link test failed at ${page.url()}: ${error.stack}\nscreenshot: ${shot}`);
  await context.close().catch(() => {});
  process.exit(1);
}
