// Opens a local HTML page in headless Chromium and reports, as JSON on stdout, every image of the
// page (its source, whether it loaded and its natural width), every console error, page error and
// failed request, and the page's title; then saves a full-page screenshot.
//
// Usage: node check-page.mjs PAGE.html SCREENSHOT.png
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
  report.images = await page.evaluate(() => Array.from(document.images, (img) => ({
    src: img.getAttribute('src'), complete: img.complete, natural_width: img.naturalWidth,
  })));
  await page.screenshot({ path: screenshot, fullPage: true });
} finally {
  await browser.close();
}
console.log(JSON.stringify(report));
