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
13 33.1882 22.2612
15 47.275 26.8216
EOD
$m2 << EOD
0 0.955556 1.06627
1 0.934059 1.21142
3 2.36264 2.34494
5 5.66609 3.89168
7 8.00302 4.9209
9 30.0403 16.4355
11 45.2037 22.338
13 44.4553 22.4407
15 65.5036 28.5655
EOD
$m3 << EOD
0 0.955556 1.06627
1 0.944719 1.20988
3 0.35727 0.23198
5 2.6485 2.50903
7 2.85435 3.49672
9 2.70356 4.82624
11 3.92594 3.14585
13 2.56523 2.31079
15 4.32003 3.26149
EOD
$m4 << EOD
0 0.955556 1.06627
1 203.721 45.454
3 275.102 39.4065
5 305.106 34.345
7 351.034 19.2829
9 345.405 22.0352
11 356.888 15.8759
13 368.23 0.298453
15 356.875 15.8425
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
