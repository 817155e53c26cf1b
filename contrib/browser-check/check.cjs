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
//     first divergence marked;
//   - in the first screenful (1400 x 900), the first scenario that did not
//     pass, with its board, check, expected, measured and by how much;
//   - every plot's marker names the pulse its scenario's failure text
//     names (one numbering, from 1, everywhere);
//   - no two text labels of a plot overlap, and none is cut off by its
//     plot's edge.
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
    const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
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
    const first = await page.evaluate(() => {
      const row = document.querySelector('table.first tr[data-scenario]');
      if (!row) return null;
      const box = row.getBoundingClientRect();
      const cells = [...row.querySelectorAll('td')].map((c) => c.textContent.trim());
      return { bottom: box.bottom, scrollY: window.scrollY, cells, scenario: row.getAttribute('data-scenario') };
    });
    const failedAny = await page.evaluate(() => document.querySelectorAll(
      'details.scenario.failed, details.scenario.error, details.scenario.flaky').length);
    if (failedAny && !first) problems.push('scenarios did not pass, and the page does not open with them');
    if (first) {
      if (first.bottom > 900) {
        problems.push(`the first scenario that did not pass (${first.scenario}) ends at ${Math.round(first.bottom)} px, below the first screenful (900 px)`);
      }
      // scenario, board, verdict, check, expected, measured, by how much
      const [name, , verdict, check, , measured] = first.cells;
      if (!name || !verdict || !check || (verdict === 'failed' && !measured)) {
        problems.push(`the first row says too little: ${JSON.stringify(first.cells)}`);
      }
    }
    const marks = await page.evaluate(() => {
      const out = [];
      for (const sc of document.querySelectorAll('details.scenario')) {
        const text = sc.querySelector('p.failure');
        // The pulse the board's value names (after "got"), else the one
        // the check names ("first divergence in pulse 42 interval").
        const said = text && (text.textContent.match(/got .*?pulse (\d+)/) || text.textContent.match(/pulse (\d+)/));
        for (const m of sc.querySelectorAll('svg.profile .divergence text, svg.profile text.divergence')) {
          const drawn = m.textContent.match(/pulse (\d+)/);
          if (said && drawn) out.push({ scenario: sc.getAttribute('data-scenario'), said: said[1], drawn: drawn[1] });
        }
      }
      return out;
    });
    for (const m of marks) {
      if (m.said !== m.drawn) problems.push(`${m.scenario}: the text says pulse ${m.said}, the plot marks pulse ${m.drawn}`);
    }
    const overlaps = await page.evaluate(() => {
      const was = [...document.querySelectorAll('details')].map((d) => [d, d.open]);
      for (const d of document.querySelectorAll('details')) d.open = true;
      const bad = [];
      for (const svg of document.querySelectorAll('svg')) {
        const frame = svg.getBoundingClientRect();
        const boxes = [...svg.querySelectorAll('text')]
          .filter((t) => t.textContent.trim())
          .map((t) => ({ t: t.textContent.trim(), b: t.getBoundingClientRect() }));
        for (const { t, b } of boxes) {
          if (b.left < frame.left - 0.5 || b.right > frame.right + 0.5) {
            bad.push(`"${t}" is cut off by its plot's edge (svg.${svg.className.baseVal})`);
          }
        }
        for (let i = 0; i < boxes.length; i += 1) {
          for (let j = i + 1; j < boxes.length; j += 1) {
            const a = boxes[i].b; const b = boxes[j].b;
            const w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
            const h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
            if (w > 1 && h > 1) bad.push(`"${boxes[i].t}" and "${boxes[j].t}" overlap (svg.${svg.className.baseVal})`);
          }
        }
        if (bad.length > 20) break;
      }
      for (const [d, open] of was) d.open = open;
      window.scrollTo(0, 0);
      return [...new Set(bad)];
    });
    problems.push(...overlaps);
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
