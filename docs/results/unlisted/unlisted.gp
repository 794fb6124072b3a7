# Written by hbirl; run `gnuplot /tmp/unl/unlisted.gp` to redraw.
$p0t0m0 << EOD
0 0.366806 0.361858
1 196.484 69.5896
3 207.718 68.611
5 289.382 55.5418
7 331.213 41.8536
EOD
$p0t0m1 << EOD
0 17.0196 12.9382
1 48.8171 46.8934
3 135.433 67.1251
5 270.009 61.4692
7 325.948 42.5127
EOD
$p0t0m2 << EOD
0 0.366748 0.361806
1 14.6349 25.2748
3 121.224 64.7079
5 258.077 63.8173
7 343.607 34.8701
EOD
$p0t0m3 << EOD
0 0.366806 0.361858
1 2.77261 3.68218
3 0.192679 0.0427214
5 2.96714 3.71576
7 0.424486 0.369586
EOD
$p0t1m0 << EOD
0 0.371685 0.361307
1 2.77261 3.68218
3 50.6479 47.3862
5 77.3148 54.5877
7 146.138 67.7038
EOD
$p0t1m1 << EOD
0 22.9264 17.0685
1 7.90895 8.85779
3 1.94106 2.66619
5 76.7798 54.2937
7 102.26 61.057
EOD
$p0t1m2 << EOD
0 0.371233 0.361302
1 2.77781 3.68167
3 0.358321 0.364989
5 1.35866 1.42288
7 36.622 40.9224
EOD
$p0t1m3 << EOD
0 0.366806 0.361858
1 2.77261 3.68218
3 0.192679 0.0427214
5 2.96714 3.71576
7 0.424486 0.369586
EOD
$p1t0m0 << EOD
0 1 0
1 0.498975 0.0015578
3 0.248812 0.00169181
5 0.166563 0.00144369
7 0.124996 0.00133853
EOD
$p1t0m1 << EOD
0 0.941175 0.00362496
1 0.681567 0.0251266
3 0.306717 0.0195797
5 0.197258 0.0199453
7 0.137383 0.00774768
EOD
$p1t0m2 << EOD
0 0.999954 6.98615e-05
1 0.771608 0.0230778
3 0.733412 0.0340249
5 0.752517 0.0499402
7 0.714654 0.0827666
EOD
$p1t0m3 << EOD
0 1 0
1 0.917483 0.00408847
3 0.933946 0.0016041
5 0.951679 0.00128306
7 0.961408 0.00101937
EOD
$p1t1m0 << EOD
0 0.999342 0.000218906
1 0.917483 0.00408847
3 0.778 0.0270572
5 0.773042 0.0359523
7 0.794937 0.0357807
EOD
$p1t1m1 << EOD
0 0.706288 0.0553541
1 0.833292 0.0136265
3 0.789704 0.0125324
5 0.787867 0.0110234
7 0.790833 0.0145632
EOD
$p1t1m2 << EOD
0 0.999254 0.00026446
1 0.917837 0.00401793
3 0.847883 0.0129332
5 0.861525 0.0100392
7 0.875896 0.00391261
EOD
$p1t1m3 << EOD
0 1 0
1 0.917483 0.00408847
3 0.933946 0.0016041
5 0.951679 0.00128306
7 0.961408 0.00101937
EOD
set grid
set key box opaque
set offsets 0.3, 0.3, 0, 0
set xlabel 'true confounding elements |E|'
set style line 1 lc rgb '#1b9e77' lw 2 pt 7
set style line 2 lc rgb '#d95f02' lw 2 pt 5
set style line 3 lc rgb '#7570b3' lw 2 pt 9
set style line 4 lc rgb '#666666' lw 2 pt 11 dt 2
set terminal pngcairo size 1100,800 noenhanced font 'sans,11'
set output '/tmp/unl/unlisted.png'
set multiplot layout 2,2 title 'Unlisted confounders (95% CI)'
set title 'ILE, told none (eta over the subject alone)'
set ylabel 'ILE'
set yrange [0:*]
set key top left
plot $p0t0m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p0t0m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p0t0m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p0t0m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'ILE, told 1 element(s)'
set ylabel 'ILE'
set yrange [0:*]
set key top left
plot $p0t1m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p0t1m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p0t1m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p0t1m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'label accuracy, told none (eta over the subject alone)'
set ylabel 'label accuracy'
set yrange [0:1.02]
set key bottom left
plot $p1t0m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p1t0m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p1t0m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p1t0m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'label accuracy, told 1 element(s)'
set ylabel 'label accuracy'
set yrange [0:1.02]
set key bottom left
plot $p1t1m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p1t1m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p1t1m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p1t1m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
unset multiplot
set terminal svg size 1100,800 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/unl/unlisted.svg'
set multiplot layout 2,2 title 'Unlisted confounders (95% CI)'
set title 'ILE, told none (eta over the subject alone)'
set ylabel 'ILE'
set yrange [0:*]
set key top left
plot $p0t0m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p0t0m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p0t0m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p0t0m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'ILE, told 1 element(s)'
set ylabel 'ILE'
set yrange [0:*]
set key top left
plot $p0t1m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p0t1m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p0t1m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p0t1m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'label accuracy, told none (eta over the subject alone)'
set ylabel 'label accuracy'
set yrange [0:1.02]
set key bottom left
plot $p1t0m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p1t0m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p1t0m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p1t0m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
set title 'label accuracy, told 1 element(s)'
set ylabel 'label accuracy'
set yrange [0:1.02]
set key bottom left
plot $p1t1m0 using 1:2:3 with yerrorlines ls 1 title 'as told', $p1t1m1 using 1:2:3 with yerrorlines ls 2 title 'catch-all, eta fixed', $p1t1m2 using 1:2:3 with yerrorlines ls 3 title 'catch-all, eta learned', $p1t1m3 using 1:2:3 with yerrorlines ls 4 title 'oracle (told every element)'
unset multiplot
unset output
