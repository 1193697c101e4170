// Browser test of `idrig serve`: Debian's Chromium, headless, driven by playwright-core (from
// tools/idrig/web/node_modules). Checks on a catalogue made by `idrig demo`: the models table
// lists the catalogue's models (the expected list comes from sqlite3, not from the server), and
// the Bode, history and gap plots are drawn with data (point counts and painted pixels).
// Usage: node dashboard_test.mjs URL EXPECTED_MODELS(id:method,...) SCREENSHOT_DIR WEB_DIR
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [url, expectedText, shots, webDir] = process.argv.slice(2);
const require = createRequire(join(webDir, 'package.json'));
const { chromium } = require('playwright-core');
const expected = expectedText.split(',').map((s) => s.split(':')).map(([id, method]) => ({ id, method }));

let failures = 0, passed = 0;
function check(ok, what) {
  if (ok) { passed++; console.log(`ok: ${what}`); } else { failures++; console.log(`FAIL: ${what}`); }
}

const profile = mkdtempSync(join(tmpdir(), 'idrig-chromium-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: '/usr/bin/chromium', headless: true, viewport: { width: 1280, height: 800 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
const errors = [];
try {
  const page = context.pages()[0] || await context.newPage();
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  const open = async (hash) => {
    await page.goto(`${url}/#${hash}`);
    await page.waitForFunction((h) => document.body.dataset.ready === h, `#${hash}`, { timeout: 15000 });
    await page.waitForTimeout(300);
  };
  // Painted pixels of the canvases inside a plot (uPlot draws on a transparent canvas).
  const painted = (selector) => page.evaluate((sel) => {
    let n = 0;
    for (const c of document.querySelectorAll(`${sel} canvas`)) {
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
    }
    return n;
  }, selector);
  const points = (selector) => page.evaluate((sel) => Number(document.querySelector(sel)?.dataset.points ?? -1), selector);

  await open('models');
  const rows = await page.$$eval('#models-table tr', (trs) => trs.slice(1).map((tr) => [...tr.children].map((td) => td.textContent)));
  check(rows.length === expected.length, `models table has ${rows.length} rows, the catalogue ${expected.length} models`);
  for (const e of expected)
    check(rows.some((r) => r[1] === e.id && r[5] === e.method), `models table lists model ${e.id} (${e.method})`);
  await page.screenshot({ path: join(shots, 'dashboard_models.png') });

  if (expected.length >= 2) {
    await open(`models?compare=${expected[0].id},${expected[1].id}`);
    const cmp = await page.$$eval('#compare-table tr', (trs) => trs.slice(1).map((tr) => [...tr.children].map((td) => td.textContent)));
    check(cmp.some((r) => r[0] === 'method' && r[1] === expected[0].method && r[2] === expected[1].method),
      `compare ${expected[0].id} and ${expected[1].id}: methods side by side`);
    check(cmp.filter((r) => /%\)$/.test(r[3])).length >= 3, 'compare has differences with relative values');
    check(await points('#bode .plot[data-kind="bode-magnitude"]') > 100, 'compare draws both Bode plots');
    await page.locator('#compare-table').screenshot({ path: join(shots, 'dashboard_compare.png') });
  }

  await open('experiments');
  const experiments = await page.$$eval('#experiments-table tr', (trs) => trs.slice(1).map((tr) => [...tr.children].map((td) => td.textContent)));
  check(experiments.length === 3 && experiments.every((r) => /^\d+\/\d+$/.test(r[7])), `experiments table: ${experiments.length} experiments, blocks stored`);
  await open(`experiments/sim1/${experiments[0][1]}`);
  const signalPoints = await page.$$eval('.uplot-box', (d) => d.map((x) => Number(x.dataset.points)));
  check(signalPoints.length === 2 && signalPoints.every((n) => n === Number(experiments[0][4])), `experiment signals u and y plotted: ${signalPoints.join(', ')} points`);
  const links = await page.$$eval('a[download]', (a) => a.map((x) => x.getAttribute('href')));
  check(links.some((h) => h.endsWith('.csv')) && links.some((h) => h.endsWith('.mat')), 'CSV and .mat export links');

  const band = expected.find((e) => e.method === 'arx') || expected[0];  // arx stores Cov(g)
  await open(`models/${band.id}`);
  const mag = await points('#bode .plot[data-kind="bode-magnitude"]'), phase = await points('#bode .plot[data-kind="bode-phase"]');
  check(mag > 100 && phase > 100, `Bode of model ${band.id}: ${mag} magnitude and ${phase} phase points`);
  const bodePixels = await painted('#bode');
  check(bodePixels > 2000, `Bode plots painted (${bodePixels} pixels)`);
  const note = await page.$eval('#bode .note', (n) => n.textContent);
  check(/±2σ/.test(note), `Bode has the confidence band of ${band.method}: "${note.slice(0, 60)}…"`);
  const pz = await points('.plot[data-kind="scatter"]');
  check(pz >= 3, `pole-zero map has ${pz} marks`);
  check(await points('.plot[data-kind="step"]') > 50, 'step response drawn');
  await page.locator('#bode').screenshot({ path: join(shots, 'dashboard_bode.png') });
  await page.locator('.plot[data-kind="step"]').locator('..').screenshot({ path: join(shots, 'dashboard_step_poles.png') });

  await open('history?rig=sim1&param=wn_1&method=');
  const h = await points('#history .plot');
  check(h === expected.length, `history of wn_1 has ${h} points (${expected.length} models)`);
  const legend = await page.$$eval('#history .u-legend .u-series', (s) => s.length);
  const methods = new Set(expected.map((e) => e.method)).size;
  check(legend === methods + 1, `history legend: ${legend - 1} series, one per method (${methods})`);
  const hp = await painted('#history');
  check(hp > 500, `history plot painted (${hp} pixels)`);
  await page.locator('#history').screenshot({ path: join(shots, 'dashboard_history.png') });

  await open('gaps/1');
  const gap = await page.$$eval('#gap-plots .svg-plot', (d) => d.map((x) => [x.dataset.name, Number(x.dataset.points)]));
  check(gap.length >= 4, `gap report has ${gap.length} plots: ${gap.map((g) => g[0]).join(', ')}`);
  check(gap.every(([, n]) => n > 0), `every gap plot has bars: ${gap.map((g) => g[1]).join(', ')}`);
  const verdict = await page.$eval('pre', (p) => p.textContent);
  check(/verdict: parameter_mismatch/.test(verdict), 'gap report text names the verdict');
  await page.locator('#gap-plots').screenshot({ path: join(shots, 'dashboard_gap.png') });

  check(errors.length === 0, `no errors in the page${errors.length ? ': ' + errors.join('; ') : ''}`);
} finally {
  await context.close();
  rmSync(profile, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failures} failed`);
process.exit(failures ? 1 : 0);
