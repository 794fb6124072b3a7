# Written by hbirl; run `gnuplot /tmp/cgs/calibration.gp` to redraw.
$d0 << EOD
0.061826 0 2.77556e-17 0.390334 0.05 6
0.147853 0 0 0.489891 0.15 4
0.241109 0.4 0.117621 0.769276 0.25 5
0.35309 0.333333 0.13812 0.609378 0.35 12
0.456576 0.285714 0.0822189 0.641066 0.45 7
0.544377 0.5 0.236593 0.763407 0.55 10
0.663622 0.5 0.236593 0.763407 0.65 10
0.760353 0.705882 0.468669 0.8672 0.75 17
0.859175 0.862069 0.69441 0.945026 0.85 29
0.978607 0.852941 0.79192 0.898364 0.95 170
EOD
$d1 << EOD
0.0116667 0.5 0.320606 0.679394 0.05 26
0.140889 0 0 0.65762 0.15 2
0.387434 0 0 0.65762 0.35 2
0.436949 0.4 0.117621 0.769276 0.45 5
0.547562 0.142857 0.0256796 0.513128 0.55 7
0.65339 0.454545 0.212713 0.719908 0.65 11
0.76177 1 0.609666 1 0.75 6
0.864265 0.8 0.548146 0.929525 0.85 15
0.987515 0.989796 0.963564 0.997197 0.95 196
EOD
set terminal pngcairo size 1000,1100 noenhanced font 'sans,11'
set output '/tmp/cgs/calibration.png'
set multiplot layout 2,1
set size 1,0.7
set origin 0,0.3
set grid
set key left top
set xrange [0:1]
set yrange [0:1]
set xlabel 'confidence (mean in bin)'
set ylabel 'share right'
set title 'Reliability: share of runs within 5% of the optimal value against the confidence (95% Wilson)'
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.102, AUROC 0.772)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.081, AUROC 0.934)'
set size 1,0.3
set origin 0,0
set title 'Runs per confidence bin'
set xlabel 'confidence'
set ylabel 'runs'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.04
plot $d0 using ($5-0.02):6 with boxes lc rgb '#d95f02' title 'observations', $d1 using ($5+0.02):6 with boxes lc rgb '#1b9e77' title 'truth'
unset multiplot
set terminal svg size 1000,1100 noenhanced font 'sans,11' background rgb 'white'
set output '/tmp/cgs/calibration.svg'
set multiplot layout 2,1
set size 1,0.7
set origin 0,0.3
set grid
set key left top
set xrange [0:1]
set yrange [0:1]
set xlabel 'confidence (mean in bin)'
set ylabel 'share right'
set title 'Reliability: share of runs within 5% of the optimal value against the confidence (95% Wilson)'
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.102, AUROC 0.772)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.081, AUROC 0.934)'
set size 1,0.3
set origin 0,0
set title 'Runs per confidence bin'
set xlabel 'confidence'
set ylabel 'runs'
set yrange [0:*]
set style fill solid 0.6
set boxwidth 0.04
plot $d0 using ($5-0.02):6 with boxes lc rgb '#d95f02' title 'observations', $d1 using ($5+0.02):6 with boxes lc rgb '#1b9e77' title 'truth'
unset multiplot
unset output
