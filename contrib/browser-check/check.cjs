#!/usr/bin/env node
// Opens a ppmc HTML report in headless Chromium from a file:// URL, as a
// person opening the CI artifact would, and checks what they would see:
//   - no console error and no uncaught page error;
//   - no request but the page itself (no script, font, style or image
//     from anywhere, the network least of all);
//   - every scenario of the table has its section, every plot is laid out
//     (a box of non-zero size) and every line holds as many points as its
//     data-points says, as the browser parsed them;
//   - with --expect-divergence NAME: that scenario's speed profile has the
//     first divergence marked.
// Saves the page's top as report.png and, when a scenario did not pass, the
// first such scenario as report-failure.png, in the folder given.
//
// usage: node check.cjs REPORT.html OUT_DIR [--expect-divergence SCENARIO]
// CHROMIUM overrides /usr/bin/chromium.
'use strict';
const path = require('path');
const { pathToFileURL } = require('url');
const { chromium } = require('playwright-core');

async function main() {
  const [report, outDir, ...rest] = process.argv.slice(2);
  if (!report || !outDir) {
    console.error('usage: node check.cjs REPORT.html OUT_DIR [--expect-divergence SCENARIO]');
    process.exit(2);
  }
  const i = rest.indexOf('--expect-divergence');
  const expectDivergence = i >= 0 ? rest[i + 1] : null;
  const url = pathToFileURL(path.resolve(report)).href;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: [
      '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
    ],
  });
  const problems = [];
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 1000 } });
    const requests = [];
    page.on('request', (r) => requests.push(r.url()));
    page.on('console', (m) => {
      if (m.type() === 'error') problems.push(`console error: ${m.text()}`);
    });
    page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
    await page.goto(url, { waitUntil: 'load' });
    for (const r of requests) {
      if (r !== url) problems.push(`request other than the page itself: ${r}`);
    }
    const seen = await page.evaluate(() => {
      const rows = [...document.querySelectorAll('table.scenarios tr')].length
        - document.querySelectorAll('table.scenarios').length;
      const sections = document.querySelectorAll('details.scenario').length;
      const bad = [];
      for (const line of document.querySelectorAll('polyline')) {
        const want = Number(line.getAttribute('data-points'));
        if (line.points.numberOfItems !== want) {
          bad.push(`a line says ${want} points and holds ${line.points.numberOfItems}`);
        }
      }
      // Lay every plot out: open every scenario, then measure.
      for (const d of document.querySelectorAll('details')) d.open = true;
      let svgs = 0;
      for (const svg of document.querySelectorAll('svg')) {
        const box = svg.getBoundingClientRect();
        if (!(box.width > 0 && box.height > 0)) bad.push(`an SVG of class ${svg.className.baseVal} has no size`);
        svgs += 1;
      }
      for (const d of document.querySelectorAll('details.scenario')) d.open = d.hasAttribute('data-open');
      return { rows, sections, bad, svgs };
    });
    problems.push(...seen.bad);
    if (seen.rows !== seen.sections) {
      problems.push(`the table lists ${seen.rows} scenarios, the page holds ${seen.sections}`);
    }
    if (expectDivergence) {
      const marks = await page.evaluate((name) => {
        const s = document.querySelector(`details.scenario[data-scenario="${name}"]`);
        return s ? s.querySelectorAll('svg.profile .divergence').length : -1;
      }, expectDivergence);
      if (marks < 0) problems.push(`no scenario ${expectDivergence} in the report`);
      else if (marks === 0) problems.push(`${expectDivergence}: no divergence marked on its speed profile`);
    }
    await page.screenshot({ path: path.join(outDir, 'report.png') });
    const failed = page.locator('details.scenario.failed, details.scenario.error, details.scenario.flaky').first();
    if (await failed.count()) {
      await failed.scrollIntoViewIfNeeded();
      await failed.screenshot({ path: path.join(outDir, 'report-failure.png') });
    }
    console.log(`browser check: ${url}: ${seen.sections} scenarios, ${seen.svgs} plots, `
      + `${requests.length} request (the page), ${problems.length} problems`);
  } finally {
    await browser.close();
  }
  for (const p of problems) console.error(`browser check: ${p}`);
  process.exit(problems.length ? 1 : 0);
}

main().catch((e) => {
  console.error(`browser check: ${e.stack || e}`);
  process.exit(1);
});
