# Written by hbirl; run `gnuplot /tmp/on_new/onion.gp` to redraw.
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
1 7.8104 0.817824
2 3.66171 0.884951
3 2.72136 0.777844
4 1.39805 0.530981
5 1.39914 0.562602
6 1.28214 0.540865
7 1.05735 0.508102
8 0.61588 0.344727
9 0.626173 0.378526
10 0.45988 0.336769
EOD
$m2 << EOD
1 5.48825 0.695574
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
1 5.43895 0.690844
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
1 3.73593 0.82263
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
set output '/tmp/on_new/onion.png'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
set terminal svg size 900,600 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/on_new/onion.svg'
plot $m0 using 1:2:3 with yerrorlines linestyle 1 title 'True Trajectories', \
     $m1 using 1:2:3 with yerrorlines linestyle 2 title 'ML Trajectories', \
     $m2 using 1:2:3 with yerrorlines linestyle 3 title 'ML Observations', \
     $m3 using 1:2:3 with yerrorlines linestyle 4 title 'Plausible eta', \
     $m4 using 1:2:3 with yerrorlines linestyle 5 title 'Uniform eta'
unset output
