// An annotator whose browser asks for Simplified Chinese: the invite, the queue and both task
// pages come in Chinese, and one forward and one inverse item are finished by keyboard alone,
// each move announced in the live region, read from the accessibility tree. Started by
// tests/service/browser.rs; parameters come as JSON in the first argument. Prints one JSON line
// of findings on success; on failure saves a screenshot and exits 1.
import { tmpdir } from "node:os";
import { join } from "node:path";
import { check, openPage, tabTo } from "./chromium.mjs";

const params = JSON.parse(process.argv[2]);
const { base } = params;

// The live region as assistive technology reads it: its node in the accessibility tree.
async function liveRegion(page) {
  const region = page.locator("#announce");
  check((await region.getAttribute("aria-live")) === "polite", "the announcer is not a polite live region");
  return region.ariaSnapshot();
}

// Puts card `label` into slot `slot` by keyboard and returns what the live region then says.
async function place(page, label, slot) {
  await tabTo(page, `.card[data-label="${label}"]`);
  await page.keyboard.press(String(slot));
  await page.waitForFunction(() => document.getElementById("save-status")?.textContent === "已保存");
  return liveRegion(page);
}

async function lang(page) {
  return page.evaluate(() => document.documentElement.lang);
}

async function finishByKeyboard(page, slots, found, name) {
  found[name] = [];
  for (let k = 1; k <= slots; k++) {
    const said = await place(page, k, k);
    check(said.includes(`已放入槽位 ${k}`), `${name}: after placing card ${k}, the live region reads ${said}`);
    found[name].push(said);
  }
  await tabTo(page, "#submit");
  const here = page.url();
  await Promise.all([page.waitForURL((url) => url.href !== here), page.keyboard.press("Enter")]);
}

async function run(page) {
  const found = {};
  await page.goto(base + params.invite);
  check((await lang(page)) === "zh-CN", `invite page lang ${await lang(page)}`);
  check((await page.textContent("h1")).startsWith("欢迎"), "the invite page is not in Chinese");
  await page.fill('input[name="password"]', "a long enough password");
  await page.fill('input[name="repeat"]', "a long enough password");
  await tabTo(page, 'button[type="submit"]');
  await Promise.all([page.waitForURL(`${base}/annotate`), page.keyboard.press("Enter")]);

  check((await lang(page)) === "zh-CN", "queue lang");
  const queue = await page.textContent("main");
  check(queue.includes("我的队列") && queue.includes("已完成 0 / 2 个条目"), `queue: ${queue}`);
  await tabTo(page, "#continue");
  await Promise.all([page.waitForURL(`${base}/annotate/mini/${params.forward}`), page.keyboard.press("Enter")]);

  // Forward: the page in Chinese, the benchmark's own text as it is.
  check((await lang(page)) === "zh-CN", "forward page lang");
  found.forward_heading = await page.textContent(".answer-column h2");
  check(found.forward_heading.includes("步骤"), `forward heading ${found.forward_heading}`);
  check((await page.textContent("#submit")).trim() === "提交答案", "submit button not in Chinese");
  check(await page.isVisible('.action [lang="en"]'), "the actions are not shown as English text");
  check((await page.getAttribute(".card img", "alt")).startsWith("候选"), "candidate alt text not in Chinese");
  await finishByKeyboard(page, params.forward_slots, found, "forward_announced");

  // Inverse, next in the queue.
  check(page.url() === `${base}/annotate/mini/${params.inverse}` || page.url().endsWith("/annotate/next"),
    `after the forward item: ${page.url()}`);
  await page.waitForURL(`${base}/annotate/mini/${params.inverse}`);
  check((await lang(page)) === "zh-CN", "inverse page lang");
  found.inverse_heading = await page.textContent(".answer-column h2");
  check(found.inverse_heading.includes("状态转变"), `inverse heading ${found.inverse_heading}`);
  await finishByKeyboard(page, params.inverse_slots, found, "inverse_announced");

  await page.waitForURL(`${base}/annotate`);
  const done = await page.textContent("main");
  check(done.includes("已完成 2 / 2 个条目"), `queue after both: ${done}`);
  return found;
}

const { context, page, consoleErrors } = await openPage({ ...params, locale: "zh-CN" });
try {
  const found = await run(page);
  check(consoleErrors.length === 0, `console errors:\n${consoleErrors.join("\n")}`);
  found.console_errors = consoleErrors.length;
  console.log(JSON.stringify({ ok: true, ...found }));
  await context.close();
} catch (error) {
  const shot = join(params.failure_dir || tmpdir(), "locale-e2e-failure.png");
  await page.screenshot({ path: shot, fullPage: true }).catch(() => {});
  console.error(`browser test failed at ${page.url()}: ${error.stack}\nscreenshot: ${shot}`);
  await context.close().catch(() => {});
  process.exit(1);
}
