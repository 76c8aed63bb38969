// Opens a local HTML page in headless Chromium and reports, as JSON on stdout, every image of the
// page (its source, whether it loaded, decoded and its natural width; lazy images are scrolled
// into view first), the rows of its tables, every console error, page error and failed request,
// and the page's title; then saves a full-page screenshot.
//
// Usage: node check-page.mjs PAGE.html SCREENSHOT.png (`-`: no screenshot)
// The browser is the system's Chromium (CHROMIUM, else /usr/bin/chromium): nothing is downloaded.
import { chromium } from 'playwright-core';
import { pathToFileURL } from 'node:url';
import { resolve } from 'node:path';

const [page_path, screenshot] = process.argv.slice(2);
if (!page_path || !screenshot) {
  console.error('usage: node check-page.mjs PAGE.html SCREENSHOT.png');
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  // No sandbox (tests may run as root); no background traffic (the machine may have no network).
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
const report = { console_errors: [], page_errors: [], failed_requests: [] };
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  page.on('console', (m) => { if (m.type() === 'error') report.console_errors.push(m.text()); });
  page.on('pageerror', (e) => report.page_errors.push(String(e)));
  page.on('requestfailed', (r) => report.failed_requests.push(`${r.url()}: ${r.failure()?.errorText}`));
  await page.goto(pathToFileURL(resolve(page_path)).href, { waitUntil: 'load', timeout: 120000 });
  report.title = await page.title();
  // Lazy images (`loading="lazy"`) load as they come into view: scroll the whole page through,
  // then wait for each image to decode (at most 20 s each).
  await page.evaluate(async () => {
    for (let y = 0; y < document.body.scrollHeight; y += window.innerHeight / 2) {
      window.scrollTo(0, y);
      await new Promise((done) => setTimeout(done, 25));
    }
    window.scrollTo(0, 0);
  });
  report.images = await page.evaluate(() => Promise.all(Array.from(document.images, async (img) => {
    const timeout = new Promise((_, fail) => setTimeout(() => fail(new Error('timeout')), 20000));
    const decoded = await Promise.race([img.decode(), timeout]).then(() => true, () => false);
    return { src: img.getAttribute('src'), complete: img.complete, natural_width: img.naturalWidth, decoded };
  })));
  // The rows of the page's tables in order (id and class), for pages that rank their rows.
  report.rows = await page.evaluate(() => Array.from(document.querySelectorAll('tbody tr'),
    (tr) => ({ id: tr.id, class: tr.className })));
  if (screenshot !== '-') await page.screenshot({ path: screenshot, fullPage: true });
} finally {
  await browser.close();
}
console.log(JSON.stringify(report));
