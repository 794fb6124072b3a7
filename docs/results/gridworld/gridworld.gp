# Written by hbirl; run `gnuplot docs/results/gridworld/gridworld.gp` to redraw.
$m0 << EOD
0 0.158338 0.0292691
1 0.158338 0.0292691
3 0.158338 0.0292691
5 0.158338 0.0292691
7 0.158338 0.0292691
9 0.158338 0.0292691
11 0.158338 0.0292691
13 0.158338 0.0292691
15 0.158338 0.0292691
EOD
$m1 << EOD
0 0.408436 0.464483
1 0.685976 1.04325
3 1.99681 3.59135
5 3.16254 3.37539
7 2.21192 1.82464
9 8.97977 11.4942
11 21.0591 19.5373
13 38.6622 24.3432
15 47.2647 26.8187
EOD
$m2 << EOD
0 0.95591 1.06625
1 0.930202 1.21157
3 2.36031 2.34506
5 5.0923 3.75108
7 7.15238 4.83061
9 29.4933 15.6309
11 46.7438 22.4439
13 44.097 22.4922
15 72.9723 31.0869
EOD
$m3 << EOD
0 0.95591 1.06625
1 0.946857 1.20979
3 0.35725 0.231982
5 2.6485 2.50903
7 2.85355 3.49676
9 2.70323 4.82625
11 3.92295 3.14466
13 2.5639 2.31089
15 4.32005 3.26103
EOD
$m4 << EOD
0 0.95591 1.06625
1 209.573 45.3588
3 263.362 40.8368
5 297.861 35.4934
7 345.101 22.0465
9 340.16 24.3809
11 367.623 1.32677
13 368.239 0.294481
15 340.214 24.4462
EOD
set title 'Gridworld: ILE vs confounding elements (65 runs per point, 95% CI)'
set xlabel 'Number of confounding elements |E|'
set ylabel 'ILE'
set key right center box opaque
set grid
set yrange [0:*]
set xrange [-0.5:15.5]
set style line 1 lc rgb '#1b9e77' lw 2 pt 7 ps 1.0
set style line 2 lc rgb '#d95f02' lw 2 pt 5 ps 1.0
set style line 3 lc rgb '#7570b3' lw 2 pt 9 ps 1.1
set style line 4 lc rgb '#e7298a' lw 2 pt 11 ps 1.1
set style line 5 lc rgb '#66a61e' lw 2 pt 13 ps 1.1
set style line 6 lc rgb '#e6ab02' lw 2 pt 3 ps 1.0
set terminal pngcairo size 900,600 noenhanced font 'sans,11'
set output 'docs/results/gridworld/gridworld.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'True Observation Function', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'Uniform eta', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Ignore CE'
set terminal svg size 900,600 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/gridworld/gridworld.svg'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'True Observation Function', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'Uniform eta', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Ignore CE'
unset output
