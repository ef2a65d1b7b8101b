#!/bin/sh
# Rebuild ../twinloop-vendor.js and ../uPlot.min.css from npm (needs node and npm;
# users and CI do not: the built files are committed).
set -e
cd "$(dirname "$0")"
npm ci --no-audit --no-fund
npx esbuild entry.js --bundle --minify --format=iife --legal-comments=eof --outfile=../twinloop-vendor.js
cp node_modules/uplot/dist/uPlot.min.css ..
