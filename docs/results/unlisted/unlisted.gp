# Written by hbirl; run `gnuplot docs/results/unlisted/unlisted.gp` to redraw.
$p0t0m0 << EOD
0 0.366806 0.361858
1 172.019 69.5743
3 219.867 67.8754
5 289.465 55.6958
7 331.216 41.854
EOD
$p0t0m1 << EOD
0 17.0196 12.9382
1 48.8171 46.8934
3 135.423 67.1216
5 257.737 63.716
7 330.975 41.8266
EOD
$p0t0m2 << EOD
0 0.366748 0.361806
1 13.8687 25.1275
3 121.217 64.7098
5 270.253 61.5812
7 343.552 34.8651
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
5 77.3671 54.5773
7 145.95 67.6186
EOD
$p0t1m1 << EOD
0 22.9264 17.0685
1 7.90895 8.85779
3 1.94106 2.66619
5 76.7798 54.2937
7 101.996 60.9409
EOD
$p0t1m2 << EOD
0 0.371233 0.361302
1 2.77781 3.68167
3 0.35188 0.365534
5 1.35866 1.42288
7 24.8723 34.1983
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
1 0.681612 0.0250274
3 0.310242 0.0203559
5 0.198696 0.0211106
7 0.138387 0.00781981
EOD
$p1t0m2 << EOD
0 0.999954 6.98615e-05
1 0.771646 0.0231576
3 0.733154 0.0339883
5 0.751238 0.0499114
7 0.715471 0.082979
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
3 0.777954 0.027053
5 0.773038 0.0359912
7 0.795758 0.0357446
EOD
$p1t1m1 << EOD
0 0.706288 0.0553541
1 0.833242 0.0136426
3 0.789808 0.0124648
5 0.787788 0.0110026
7 0.790404 0.0147927
EOD
$p1t1m2 << EOD
0 0.999254 0.00026446
1 0.917829 0.00402263
3 0.847858 0.0129313
5 0.861525 0.0100392
7 0.875867 0.00393314
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
set output 'docs/results/unlisted/unlisted.png'
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
set output 'docs/results/unlisted/unlisted.svg'
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
