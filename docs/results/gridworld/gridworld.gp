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
11 20.9637 19.4324
13 33.1882 22.2612
15 46.985 26.8368
EOD
$m2 << EOD
0 0.800337 1.04799
1 0.744602 1.04144
3 2.98533 3.74006
5 10.4537 6.37425
7 21.8599 10.6568
9 47.6636 17.4404
11 84.5873 26.4981
13 54.5609 19.9878
15 93.9669 27.403
EOD
$m3 << EOD
0 0.800337 1.04799
1 1.48129 1.76749
3 1.9827 2.35246
5 3.40613 2.90528
7 8.04035 4.38621
9 7.63144 5.99387
11 12.2764 5.1307
13 9.5062 4.26449
15 16.0398 6.96075
EOD
$m4 << EOD
0 0.800337 1.04799
1 82.6802 37.8576
3 228.023 44.0237
5 328.52 28.3647
7 368.316 0.173512
9 367.917 1.05981
11 368.475 0.0211228
13 368.361 0.260674
15 368.449 0.0680197
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
set terminal pngcairo size 900,600 font 'sans,11'
set output 'docs/results/gridworld/gridworld.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'True Observation Function', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'Uniform eta', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Ignore CE'
set terminal svg size 900,600 font 'sans,11' background rgb 'white'
set output 'docs/results/gridworld/gridworld.svg'
replot
unset output
