# Written by hbirl; run `gnuplot docs/results/onion/onion.gp` to redraw.
$m0 << EOD
1 5.38966 0.685941
2 0 0
3 0 0
4 0 0
5 0 0
6 0 0
7 0 0
8 0 0
9 0 0
10 0 0
EOD
$m1 << EOD
1 7.32885 0.867371
2 3.7305 0.890171
3 3.06533 0.82057
4 1.8796 0.652383
5 1.88069 0.678338
6 1.14455 0.496823
7 1.12614 0.53074
8 0.753466 0.412705
9 0.626173 0.378526
10 0.735052 0.467224
EOD
$m2 << EOD
1 4.52514 0.674156
2 0 0
3 0 0
4 0 0
5 0 0
6 0 0
7 0 0
8 0 0
9 0 0
10 0 0
EOD
$m3 << EOD
1 4.68223 0.676358
2 0 0
3 0 0
4 0 0
5 0 0
6 0 0
7 0 0
8 0 0
9 0 0
10 0 0
EOD
$m4 << EOD
1 2.70404 0.706148
2 0 0
3 0 0
4 0 0
5 0 0
6 0 0
7 0 0
8 0 0
9 0 0
10 0 0
EOD
set title 'Onion sorting: ILE vs trajectories (100 runs per point, 95% CI)'
set xlabel 'Number of trajectories'
set ylabel 'ILE'
set key right center box opaque
set grid
set yrange [0:*]
set xrange [0.5:10.5]
set style line 1 lc rgb '#1b9e77' lw 2 pt 7 ps 1.0
set style line 2 lc rgb '#d95f02' lw 2 pt 5 ps 1.0
set style line 3 lc rgb '#7570b3' lw 2 pt 9 ps 1.1
set style line 4 lc rgb '#e7298a' lw 2 pt 11 ps 1.1
set style line 5 lc rgb '#66a61e' lw 2 pt 13 ps 1.1
set style line 6 lc rgb '#e6ab02' lw 2 pt 3 ps 1.0
set terminal pngcairo size 900,600 noenhanced font 'sans,11'
set output 'docs/results/onion/onion.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
set terminal svg size 900,600 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/onion/onion.svg'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
unset output
