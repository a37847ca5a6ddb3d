import { defineConfig } from 'vitest/config';
import preact from '@preact/preset-vite';

// The app is embedded in the `sfc` binary from `web/dist` (rust-embed, see crates/sfc-server).
export default defineConfig({
  plugins: [preact()],
  base: './',
  build: { outDir: 'dist', emptyOutDir: true, sourcemap: false, chunkSizeWarningLimit: 2000 },
  test: { environment: 'jsdom', include: ['test/**/*.test.ts', 'test/**/*.test.tsx'] },
});
