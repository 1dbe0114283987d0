#!/bin/sh
# Rebuild the geometric tables this folder ships (the scripts read them; they
# are outputs of the geometry alone). Times on one free core; the venv python
# (numpy) for the rasters, plain python3 for the gap tables.
set -e
cd "$(dirname "$0")"
PY=${PY:-python3}                 # a python with numpy: the repository venv's bin/python
python3 gaptab.py > /dev/null                                   # gaptab.csv, ~2 min
DRA_MM=0.05 GAPTAB=gaptab_dra05.csv python3 gaptab.py > /dev/null   # tips broken by 0.05 mm, ~2 min
CUT=loa $PY sectab.py                                          # sectab.csv (split by the LOA only), ~2 min
$PY sectab.py                                                  # core of sectab_cut.csv, L -7.2..0.2, ~5 min
SECTAB_L0=-9.6 SECTAB_L1=-7.22 SECTAB_DL=0.04 SECTAB_X0=8 SECTAB_X1=25 SECTAB_Y=14 SECTAB=ext_lo.csv $PY sectab.py
SECTAB_L0=0.24 SECTAB_L1=2.6 SECTAB_DL=0.04 SECTAB_X0=8 SECTAB_X1=26 SECTAB_Y=14 SECTAB=ext_hi.csv $PY sectab.py
$PY merge.py sectab_cut.csv ext_lo.csv sectab_cut.csv ext_hi.csv
GROOVE_BAND_MM=40 SECTAB_L0=-5.0 SECTAB_L1=-2.0 SECTAB=wb_mid.csv $PY sectab.py
$PY merge.py sectab_cut_wideband.csv sectab_cut.csv wb_mid.csv
rm -f ext_lo.csv ext_hi.csv wb_mid.csv
