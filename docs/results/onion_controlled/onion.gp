# Written by hbirl; run `gnuplot /tmp/onc/onion.gp` to redraw.
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
1 6.02126 0.755679
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
$m2 << EOD
1 5.66483 0.683743
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
1 5.80242 0.680985
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
1 1.6185 0.146073
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
set title 'Onion sorting (scene: controlled): ILE vs trajectories (100 runs per point, 95% CI)'
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
set output '/tmp/onc/onion.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
set terminal svg size 900,600 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/onc/onion.svg'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
unset output
