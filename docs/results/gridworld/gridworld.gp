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
1 0.682927 1.04335
3 1.99675 3.59135
5 3.11217 3.37752
7 2.20689 1.82467
9 8.88425 11.4984
11 20.3319 19.1592
13 20.7218 16.6113
15 35.5188 22.7557
EOD
$m2 << EOD
0 0.802689 1.04592
1 0.820491 1.05111
3 2.98623 3.7396
5 9.56036 6.09343
7 18.2939 9.56727
9 41.9165 18.0096
11 73.1392 26.6275
13 42.6848 16.4856
15 79.0345 26.7321
EOD
$m3 << EOD
0 0.802689 1.04592
1 1.47963 1.76758
3 1.74331 2.34605
5 3.8127 3.6092
7 7.74779 4.3168
9 6.71812 4.62228
11 11.5069 5.04064
13 9.10031 4.2779
15 17.0987 7.72779
EOD
$m4 << EOD
0 0.802689 1.04592
1 85.1457 38.6942
3 217.732 43.7888
5 340.093 24.4803
7 364.748 7.25906
9 367.912 1.05326
11 367.871 1.0597
13 368.3 0.286088
15 368.382 0.208493
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
