// tests/studio/studio_browser.mjs -- the studio's page in a real browser (run by test_studio_browser.sh):
// Debian's Chromium, headless, driven by playwright-core.
//
//   node studio_browser.mjs URL NPM_DIR OUT_DIR
//
// Loads the page (the server has a generated bodice open and runs it), draws a seam stroke across its
// front through the page's own mouse events in "Draw seam" mode, and checks that the new layout has a
// seam within 2 mean edge lengths of the stroke (90 % of the stroke's points; there was none before)
// and that the pattern view draws that seam's two sides; changes S and checks the piece count changes;
// hovers a piece for its tooltip; erases the stroke; draws a grain stroke and checks a piece is turned by it;
// downloads the DXF. Screenshots go to OUT_DIR. Prints
// "N passed, M failed"; exit 1 when a check failed.
// SPDX-License-Identifier: GPL-3.0-or-later
import { createRequire } from 'node:module';
import { writeFileSync, readFileSync } from 'node:fs';

const [url, npmDir, outDir] = process.argv.slice(2);
const { chromium } = createRequire(`${npmDir}/`)('playwright-core');
let passed = 0, failed = 0;
function check(what, ok, detail = '') {
  if (ok) ++passed;
  else { ++failed; console.log(`FAIL: ${what} ${detail}`); }
}

// Distance from p to the polyline of flat xyz points.
function distanceToPolyline(p, flat) {
  let best = Infinity;
  for (let i = 0; i + 5 < flat.length; i += 3) {
    const a = flat.slice(i, i + 3), b = flat.slice(i + 3, i + 6);
    const ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    const length2 = ab[0] ** 2 + ab[1] ** 2 + ab[2] ** 2;
    const t = length2 > 0 ? Math.max(0, Math.min(1, (ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / length2)) : 0;
    best = Math.min(best, Math.hypot(ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]));
  }
  return best;
}

// The share of the stroke's points within `reach` of some seam, and the seams that come that close.
function coverage(stroke, seams, reach) {
  const near = new Set();
  let close = 0;
  for (const p of stroke) {
    let hit = false;
    seams.forEach((seam, index) => {
      if (seam.kind === 'seam' && distanceToPolyline(p, seam.points) <= reach) { hit = true; near.add(index); }
    });
    if (hit) ++close;
  }
  return { share: close / stroke.length, near };
}

// A mouse drag from (x0, y0) to (x1, y1) in `steps` moves, as a designer draws a stroke.
async function drag(page, x0, y0, x1, y1, steps) {
  await page.mouse.move(x0, y0);
  await page.mouse.down();
  for (let i = 1; i <= steps; ++i) await page.mouse.move(x0 + (x1 - x0) * i / steps, y0 + (y1 - y0) * i / steps);
  await page.mouse.up();
}

async function waitForRun(page, after) {
  await page.waitForFunction((run) => Number(document.body.dataset.run || 0) > run &&
    window.studio.state.shownRun === window.studio.state.run && !window.studio.state.refining, after,
  { timeout: 180000 });
  return page.evaluate(() => window.studio.state.shownRun);
}

const browser = await chromium.launch({
  executablePath: process.env.PZ_CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 800 }, acceptDownloads: true });
  page.on('pageerror', (error) => errors.push(String(error)));
  const outside = [];
  page.on('request', (request) => { if (!request.url().startsWith(url)) outside.push(request.url()); });
  await page.goto(url);
  const opened = await waitForRun(page, 0);
  // The first layout came with its consolidated run ("fewest pieces", ticked by default). The checks below
  // are of strokes, S and downloads: without consolidation each edit costs one run, not two (the
  // sanitizer build's runs are several times slower); consolidation is the CLI tests' (test_cli_consolidate).
  check('the page opened with "fewest pieces" ticked', await page.isChecked('#consolidate'));
  await page.uncheck('#consolidate');
  const first = await waitForRun(page, opened);
  const before = await page.evaluate(() => ({ result: window.studio.state.result, garment: window.studio.state.garment }));
  const reach = 2 * before.garment.mean_edge_mm;
  await page.screenshot({ path: `${outDir}/studio-loaded.png` });

  // A stroke across the front, drawn with the mouse in "Draw seam" mode.
  await page.click('#mode-draw');
  const box = await page.locator('#canvas3d').boundingBox();
  // Diagonally over the upper front, where the default layouts put no seam.
  const x0 = box.x + box.width * 0.40, y0 = box.y + box.height * 0.24;
  const x1 = box.x + box.width * 0.60, y1 = box.y + box.height * 0.40;
  await drag(page, x0, y0, x1, y1, 40);
  const second = await waitForRun(page, first);
  const after = await page.evaluate(() => ({ result: window.studio.state.result, strokes: window.studio.state.strokes }));
  check('one stroke recorded', after.strokes.length === 1, `(${after.strokes.length})`);
  const stroke = after.strokes.length ? after.strokes[0].points : [];
  check('the stroke has points along its length', stroke.length >= 10, `(${stroke.length})`);
  // Snapped to the surface: every point within a mean edge of a garment vertex.
  const positions = before.garment.mesh.positions;
  const offSurface = stroke.filter((p) => {
    let best = Infinity;
    for (let i = 0; i < positions.length; i += 3)
      best = Math.min(best, Math.hypot(p[0] - positions[i], p[1] - positions[i + 1], p[2] - positions[i + 2]));
    return best > before.garment.mean_edge_mm;
  });
  check('the stroke lies on the surface', offSurface.length === 0, `(${offSurface.length} points off it)`);
  const old = coverage(stroke, before.result.seams, reach);
  const now = coverage(stroke, after.result.seams, reach);
  console.log(`stroke: ${stroke.length} points; within 2 mean edges of a seam: before ${(100 * old.share).toFixed(0)} %,` +
    ` after ${(100 * now.share).toFixed(0)} %; pieces ${before.result.panel_count} -> ${after.result.panel_count}`);
  check('no seam ran along the stroke before it was drawn', old.share < 0.5, `(${old.share})`);
  check('a seam runs within 2 mean edges of the stroke', now.share >= 0.9, `(${now.share})`);
  for (const index of now.near) {
    const drawn = await page.locator(`#pattern polyline[data-seam="${index}"]`).count();
    check(`the pattern view draws both sides of seam ${index}`, drawn === 2, `(${drawn})`);
  }
  const marked = await page.locator('#pattern polyline.stroked').evaluateAll((lines) => lines.map((l) => Number(l.dataset.seam)));
  check('the pattern view marks the stroke\'s seams', marked.length > 0 && marked.every((index) => now.near.has(index)),
    `(${marked} of ${[...now.near]})`);
  check('the pattern view shows every piece',
    await page.locator('#pattern polygon.piece').count() === after.result.panel_count);
  await page.screenshot({ path: `${outDir}/studio-stroke.png` });

  // Hover a piece: its name, size and strain.
  await page.locator('#pattern polygon.piece').first().hover({ force: true });
  const tip = await page.locator('#tooltip').innerText();
  check('hovering a piece shows its name, size and strain', /mm/.test(tip) && /strain/.test(tip), `(${tip})`);

  // A stricter S: the piece count changes.
  await page.fill('#max-strain', '0.02');
  await page.locator('#max-strain').dispatchEvent('change');
  await waitForRun(page, second);
  const strict = await page.evaluate(() => window.studio.state.result);
  console.log(`S 0.05 -> 0.02: pieces ${after.result.panel_count} -> ${strict.panel_count}`);
  check('S = 0.02 was used', strict.verdict.max_strain === 0.02, `(${strict.verdict.max_strain})`);
  check('changing S changes the piece count', strict.panel_count !== after.result.panel_count,
    `(${after.result.panel_count} and ${strict.panel_count})`);
  check('the pattern view follows', await page.locator('#pattern polygon.piece').count() === strict.panel_count);
  await page.screenshot({ path: `${outDir}/studio-strict.png` });

  // Erase: a click on the stroke in "Erase" mode removes it and runs again.
  await page.click('#mode-erase');
  const [ex, ey] = await page.evaluate((p) => window.studio.project(p), stroke[Math.floor(stroke.length / 2)]);
  await page.mouse.click(ex, ey);
  const erasedRun = await waitForRun(page, await page.evaluate(() => window.studio.state.shownRun));
  check('erasing removes the stroke', await page.evaluate(() => window.studio.state.strokes.length) === 0);
  check('erasing runs again', erasedRun > 0);

  // A grain stroke: a short diagonal stroke in "Grain" mode turns the warp of the piece it lies on (a bias
  // cut): the result has a piece turned by about the stroke's angle to the garment's vertical (the generated
  // bodice's grain is +z, and the front faces the camera: about 40 degrees on the screen). Fails if the
  // strokes are not sent, not honoured or given to no piece.
  await page.click('#mode-grain');
  const beforeGrain = await page.evaluate(() => window.studio.state.shownRun);
  const gx0 = box.x + box.width * 0.44, gy0 = box.y + box.height * 0.70;
  const gx1 = box.x + box.width * 0.52, gy1 = box.y + box.height * 0.60;
  await drag(page, gx0, gy0, gx1, gy1, 20);
  await waitForRun(page, beforeGrain);
  const grained = await page.evaluate(() => ({ result: window.studio.state.result,
    grain: window.studio.state.grainStrokes, seams: window.studio.state.strokes }));
  check('one grain stroke recorded, no seam stroke', grained.grain.length === 1 && grained.seams.length === 0,
    `(${grained.grain.length}, ${grained.seams.length})`);
  const turned = grained.result.pieces.filter((piece) => Math.abs(piece.grain_turn_deg || 0) > 1);
  console.log(`grain stroke: pieces turned ${turned.map((piece) => `${piece.name} ${piece.grain_turn_deg}`).join(', ')}`);
  check('a piece is turned by the grain stroke (20-70 degrees)', turned.length >= 1 &&
    turned.every((piece) => Math.abs(piece.grain_turn_deg) >= 20 && Math.abs(piece.grain_turn_deg) <= 70),
    `(${turned.map((piece) => piece.grain_turn_deg)})`);
  await page.screenshot({ path: `${outDir}/studio-grain.png` });
  if (turned.length) {
    await page.locator(`#pattern polygon.piece[data-name="${turned[0].name}"]`).hover({ force: true });
    const grainTip = await page.locator('#tooltip').innerText();
    check('hovering the turned piece names its grain turn', /grain turned/.test(grainTip), `(${grainTip})`);
  }

  // The DXF through the page's download button.
  const [download] = await Promise.all([page.waitForEvent('download', { timeout: 60000 }), page.click('#download-dxf')]);
  await download.saveAs(`${outDir}/pattern.dxf`);
  const dxf = readFileSync(`${outDir}/pattern.dxf`, 'utf8');
  check('the DXF downloads', /SECTION/.test(dxf) && /ENTITIES/.test(dxf) && /EOF/.test(dxf), `(${dxf.length} bytes)`);
  check('nothing was fetched from another address', outside.length === 0, outside.join(' '));
} catch (error) {
  check('the page works', false, String(error));
} finally {
  await browser.close();
}
check('no script error on the page', errors.length === 0, errors.join(' | '));
writeFileSync(`${outDir}/summary.txt`, `${passed} passed, ${failed} failed\n`);
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
