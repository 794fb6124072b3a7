# Written by hbirl; run `gnuplot /tmp/onr/onion_regimes.gp` to redraw.
$p0m0 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p0m1 << EOD
0 1.89925 2.03232
0.3 1.46929 1.77913
0.6 1.46929 1.77913
0.9 1.03933 1.44508
EOD
$p0m2 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p0m3 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p0m4 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p1m0 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p1m1 << EOD
0 1.89925 2.03232
0.3 1.46929 1.77913
0.6 1.46929 1.77913
0.9 1.03933 1.44508
EOD
$p1m2 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p1m3 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p1m4 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p2m0 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p2m1 << EOD
0 3.24666 2.40364
0.3 1.28308 1.43554
0.6 2.57295 2.18299
0.9 1.03933 1.44508
EOD
$p2m2 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p2m3 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p2m4 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p3m0 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p3m1 << EOD
0 3.24666 2.40364
0.3 1.28308 1.43554
0.6 2.57295 2.18299
0.9 1.03933 1.44508
EOD
$p3m2 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p3m3 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
$p3m4 << EOD
0 0 0
0.3 0 0
0.6 0 0
0.9 0 0
EOD
set grid
set key top left box opaque font ',9'
set yrange [0:*]
set xrange [-0.05:0.95]
set xlabel 'foreground person in front of the expert (share of the time)'
set ylabel 'ILE'
set style line 1 lc rgb '#1b9e77' lw 2 pt 7
set style line 2 lc rgb '#d95f02' lw 2 pt 5
set style line 3 lc rgb '#7570b3' lw 2 pt 9
set style line 4 lc rgb '#e7298a' lw 2 pt 11
set style line 5 lc rgb '#66a61e' lw 2 pt 13
set terminal pngcairo size 1200,850 noenhanced font 'sans,11'
set output '/tmp/onr/onion_regimes.png'
set multiplot layout 2,2 title 'Onion sorting: ILE vs the foreground person''s share (95% CI)'
set title 'no mirror, eta as stated'
plot $p0m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p0m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p0m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p0m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p0m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'no mirror, eta overconfident (power 3)'
plot $p1m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p1m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p1m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p1m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p1m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'with the mirror, eta as stated'
plot $p2m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p2m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p2m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p2m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p2m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'with the mirror, eta overconfident (power 3)'
plot $p3m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p3m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p3m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p3m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p3m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
unset multiplot
set terminal svg size 1200,850 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/onr/onion_regimes.svg'
set multiplot layout 2,2 title 'Onion sorting: ILE vs the foreground person''s share (95% CI)'
set title 'no mirror, eta as stated'
plot $p0m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p0m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p0m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p0m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p0m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'no mirror, eta overconfident (power 3)'
plot $p1m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p1m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p1m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p1m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p1m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'with the mirror, eta as stated'
plot $p2m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p2m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p2m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p2m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p2m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
set title 'with the mirror, eta overconfident (power 3)'
plot $p3m0 using 1:2:3 with yerrorlines ls 1 title 'ML Observations', $p3m1 using 1:2:3 with yerrorlines ls 2 title 'ML Trajectories', $p3m2 using 1:2:3 with yerrorlines ls 3 title 'Plausible eta', $p3m3 using 1:2:3 with yerrorlines ls 4 title 'True Trajectories', $p3m4 using 1:2:3 with yerrorlines ls 5 title 'Uniform eta'
unset multiplot
unset output
