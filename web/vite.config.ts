import { defineConfig } from 'vitest/config';
import preact from '@preact/preset-vite';

// The app is embedded in the `sfc` binary from `web/dist` (rust-embed, see crates/sfc-server).
// `vite build --mode test` builds the test build into `web/dist-test`: the same app with the
// browser tests' hook `window.__sfc` (web/src/app/probe.ts), which production builds leave out.
export default defineConfig(({ mode }) => ({
  plugins: [preact()],
  base: './',
  build: { outDir: mode === 'test' ? 'dist-test' : 'dist', emptyOutDir: true, sourcemap: false, chunkSizeWarningLimit: 2000 },
  test: { environment: 'jsdom', include: ['test/**/*.test.ts', 'test/**/*.test.tsx'] },
}));
