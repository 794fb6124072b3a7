# Written by hbirl; run `gnuplot docs/results/gridworld_tied/gridworld.gp` to redraw.
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
0 0.185254 0.0271028
1 0.341556 0.225424
3 1.63842 2.34515
5 6.03844 5.97696
7 12.1678 12.5513
9 24.1 19.1808
11 47.8939 27.399
13 39.659 24.6182
15 77.3364 33.1959
EOD
$m3 << EOD
0 0.185254 0.0271028
1 0.254589 0.168513
3 0.281993 0.162487
5 1.21845 1.8693
7 1.58316 2.34634
9 2.4148 3.2466
11 3.0973 2.92276
13 2.77063 2.87867
15 6.99503 5.60745
EOD
$m4 << EOD
0 0.185254 0.0271028
1 270.875 40.1069
3 354.352 16.4201
5 368.369 0.208691
7 368.32 0.237965
9 368.459 0.0367197
11 368.482 0.0053218
13 368.482 0.005479
15 368.484 0.0049839
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
set output 'docs/results/gridworld_tied/gridworld.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'True Observation Function', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'Uniform eta', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Ignore CE'
set terminal svg size 900,600 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/gridworld_tied/gridworld.svg'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'True Observation Function', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'Uniform eta', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Ignore CE'
unset output
