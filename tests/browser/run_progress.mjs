// A model run's admin page in headless Chromium: logs in, checks every control of the runs
// page has a label, opens the run's page while the run is being worked, pauses and resumes it
// with the keyboard only, then waits, without reloading, until the page's script shows the run
// done. Started by tests/service/browser.rs; parameters come as JSON in the first argument
// (base, name, password, run). Prints one JSON line.
import { openPage } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { context, page, consoleErrors } = await openPage(params, 30000);
const text = (field) => page.locator(`[data-field="${field}"]`).first().innerText();

/// Tabs through the page until the button named `name` has the focus, then presses Enter.
async function pressByKeyboard(name) {
  for (let i = 0; i < 200; i++) {
    await page.keyboard.press("Tab");
    const focused = await page.evaluate(() => document.activeElement && document.activeElement.textContent.trim());
    if (focused === name) {
      await Promise.all([page.waitForNavigation(), page.keyboard.press("Enter")]);
      return;
    }
  }
  throw new Error(`the keyboard never reached the button "${name}"`);
}

try {
  await page.goto(`${params.base}/login`);
  await page.getByLabel("Name").fill(params.name);
  await page.getByLabel("Password").fill(params.password);
  await Promise.all([page.waitForNavigation(), page.getByLabel("Password").press("Enter")]);

  await page.goto(`${params.base}/admin/runs`);
  const unlabelled = await page.evaluate(() =>
    [...document.querySelectorAll("form input:not([type=hidden]), form select")]
      .filter((el) => el.labels.length === 0)
      .map((el) => el.name)
  );

  await page.goto(`${params.base}/admin/runs/${params.run}`);
  const first = { stage: await text("stage"), done: await text("done") };
  await pressByKeyboard("Pause run");
  const paused = {
    notice: await page.locator("p.notice").innerText(),
    stage: await text("stage"),
    resume_visible: await page.getByRole("button", { name: "Resume run" }).isVisible(),
    pause_visible: await page.getByRole("button", { name: "Pause run" }).isVisible(),
  };
  await pressByKeyboard("Resume run");
  const resumed = { stage: await text("stage"), done: await text("done") };
  // From here the page is never reloaded: its script alone must bring it to the end.
  let navigations = 0;
  page.on("framenavigated", () => navigations++);
  await page
    .waitForFunction(
      // The job's end, not the run's "submitted": the job is marked done just after the run
      // submits, and the page keeps polling until the job has ended.
      () => /^(done|failed|cancelled)/.test(document.querySelector('[data-field="stage"]').textContent),
      null,
      { timeout: 60000, polling: 100 }
    )
    .catch(async (e) => {
      throw new Error(`the page never showed the run's job ended: stage "${await text("stage")}", done "${await text("done")}"; console: ${consoleErrors.join("; ")}; ${e.message}`);
    });
  const last = {
    stage: await text("stage"),
    done: await text("done"),
    cost: await text("cost"),
    tokens: await text("tokens"),
    pause_visible: await page.getByRole("button", { name: "Pause run" }).isVisible(),
    cancel_visible: await page.getByRole("button", { name: "Cancel run" }).isVisible(),
  };
  if (consoleErrors.length) throw new Error(`console errors:\n${consoleErrors.join("\n")}`);
  console.log(JSON.stringify({ ok: true, unlabelled, first, paused, resumed, last, navigations }));
  await context.close();
} catch (error) {
  console.error(`run page failed at ${page.url()}: ${error.stack}`);
  await context.close().catch(() => {});
  process.exit(1);
}
