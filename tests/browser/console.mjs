// The web console in a real browser (issue 20): headless Debian Chromium driven by playwright-core
// against graspd on loopback (scripts/browser-test.sh starts it with a token and the 2F-85
// imported). The page loads its hands once the token is typed, plans on the example cloud and
// draws graspd's own glTF scene; the test checks what the scene holds — the points, the
// contacts, the opposition, the hand at the grasp — and the figures, and keeps a screenshot.
// Then it uploads a hand as a folder (HAND_FOLDER) and plans for it on an RGB-D pair (RGB,
// DEPTH).
//
// Usage: BROWSER_TOOLS=DIR node console.mjs URL TOKEN SCREENSHOT.png (DIR holds node_modules
// with playwright-core: scripts/browser-test.sh installs it in .tools/browser).
import { createRequire } from 'node:module';

const { chromium } = createRequire(`${process.env.BROWSER_TOOLS}/package.json`)('playwright-core');

const [url, token, screenshot] = process.argv.slice(2);
const fail = (message) => { console.error(`console test: ${message}`); process.exitCode = 1; };

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: [
    '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync',
    // WebGL without a GPU: the software rasteriser.
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
  ],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url);
  // Without the token the hand list is refused (401): the page says so.
  await page.waitForFunction(() => document.getElementById('status').classList.contains('error'));
  await page.fill('#token', token);
  await page.dispatchEvent('#token', 'change');
  await page.waitForSelector('#hand option[value="robotiq_2f85"]', { state: 'attached' });
  await page.selectOption('#hand', 'robotiq_2f85');
  await page.click('#example');
  await page.waitForFunction(() => !document.getElementById('plan').disabled);
  await page.click('#plan');
  await page.waitForFunction(() => window.graspdScene || document.getElementById('status')
    .classList.contains('error'), null, { timeout: 60000 });
  const result = await page.evaluate(() => ({
    scene: window.graspdScene,
    status: document.getElementById('status').textContent,
    figures: document.getElementById('figures').textContent,
  }));
  if (!result.scene) {
    fail(`no scene: ${result.status}`);
  } else {
    const nodes = result.scene.nodes;
    for (const name of ['cloud', 'support_plane', 'contacts', 'contact_normals', 'opposition']) {
      if (!nodes.includes(name)) fail(`the scene lacks ${name}: ${nodes.join(', ')}`);
    }
    for (const configuration of ['pregrasp/', 'grasp/', 'squeeze/']) {
      if (!nodes.some((n) => n.startsWith(configuration))) {
        fail(`the scene has no hand at ${configuration}`);
      }
    }
    const plan = result.scene.plan;
    if (plan.hand !== 'robotiq_2f85') fail(`planned for ${plan.hand}`);
    if (!result.figures.includes(plan.grasp_type)) fail(`figures: ${result.figures}`);
    // The canvas was drawn: some pixels differ from the background.
    const drawn = await page.evaluate(() => {
      const c = document.querySelector('#view canvas');
      const gl = c.getContext('webgl2') || c.getContext('webgl');
      const px = new Uint8Array(4 * 64 * 64);
      gl.readPixels(c.width / 2 - 32, c.height / 2 - 32, 64, 64, gl.RGBA, gl.UNSIGNED_BYTE, px);
      let differing = 0;
      for (let i = 0; i < px.length; i += 4) {
        if (Math.abs(px[i] - 250) > 12 || Math.abs(px[i + 1] - 250) > 12) differing++;
      }
      return differing;
    });
    if (drawn < 20) fail(`the view's centre is empty (${drawn} drawn pixels of 4096)`);
    console.log(`console test: ${nodes.length} scene nodes, ${plan.grasp_type}, ` +
                `feasible ${plan.feasible}, ${drawn} drawn pixels at the centre`);
  }
  await page.screenshot({ path: screenshot });

  // A hand uploaded as a folder (the shared 2F-85's MJCF and meshes), then planned for.
  await page.click('#register summary');
  await page.fill('#hand-name', 'uploaded_2f85');
  await page.setInputFiles('#hand-folder', process.env.HAND_FOLDER);
  await page.click('#hand-upload');
  await page.waitForFunction(() => /registered|hand:/.test(
    document.getElementById('status').textContent), null, { timeout: 60000 });
  const registered = await page.evaluate(() => document.getElementById('status').textContent);
  if (!registered.includes('uploaded_2f85 registered')) fail(`upload: ${registered}`);
  if (await page.inputValue('#hand') !== 'uploaded_2f85') fail('the uploaded hand is not chosen');

  // An RGB-D frame (the example pair) planned for it.
  await page.click('#rgbd summary');
  await page.setInputFiles('#color', process.env.RGB);
  await page.setInputFiles('#depth', process.env.DEPTH);
  await page.evaluate(() => { window.graspdScene = null; });
  await page.click('#plan');
  await page.waitForFunction(() => window.graspdScene || document.getElementById('status')
    .classList.contains('error'), null, { timeout: 60000 });
  const frame = await page.evaluate(() => ({
    scene: window.graspdScene,
    status: document.getElementById('status').textContent,
  }));
  if (!frame.scene) {
    fail(`RGB-D: ${frame.status}`);
  } else {
    const nodes = frame.scene.nodes;
    if (!nodes.includes('cloud') || !nodes.some((n) => n.startsWith('grasp/'))) {
      fail(`RGB-D scene: ${nodes.join(', ')}`);
    }
    if (!frame.scene.plan.perception) fail('RGB-D: the plan has no perception report');
    console.log(`console test: RGB-D with the uploaded hand, ${nodes.length} scene nodes, ` +
                `${frame.scene.plan.grasp_type}`);
  }
  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
} finally {
  await browser.close();
}
