#!/usr/bin/env bash
# Draws the contact-model loops committed to the documentation (docs/img/contact_*.png)
# with `cohdem contact`: MEPA n = 3/2 with the copper ore parameters of the MEPA paper
# (Table 1, 5% moisture; k in N/m^1.5) and Walton's model for a micron powder.
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${COHDEM_BIN:-build/cohdem}
out=$(mktemp -d)
"$bin" contact --model mepa --rolling epsd --set k1=4.75e8 --set k2=2.37e9 --set kadh=3.56e8 --set n=1.5 \
  --set mu=0.35 --set mu_r=0.3 --ri 3.175e-3 --path examples/contact/mepa_cycle.csv --out "$out/mepa"
"$bin" contact --model walton --set Y=1e8 --set Fc0=1e-7 --set mu=0.3 --set cf=0.01 --set bf=1 --set tf=1 --set gap_c=1e-9 \
  --E 1e10 --nu 0.3 --ri 5e-6 --path examples/contact/walton_moments.csv --out "$out/walton"
cp "$out/mepa/response.png" docs/img/contact_mepa_n1.5.png
cp "$out/walton/response.png" docs/img/contact_walton.png
cp "$out/mepa/response.csv" docs/img/contact_mepa_n1.5.csv
cp "$out/walton/response.csv" docs/img/contact_walton.csv
rm -rf "$out"
echo "wrote docs/img/contact_mepa_n1.5.png and docs/img/contact_walton.png"
