# Written by hbirl; run `gnuplot docs/results/calibration_onion/calibration.gp` to redraw.
$d0 << EOD
0.283317 0 0 0.128729 0.25 26
0.328882 0 0 0.049992 0.35 73
0.406318 0 0 0.793451 0.45 1
0.999998 1 0.981155 1 0.95 200
EOD
$d1 << EOD
0.275028 0 0 0.11697 0.25 29
0.334639 0 0 0.051328 0.35 71
0.999998 1 0.981155 1 0.95 200
EOD
set terminal pngcairo size 1000,1100 noenhanced font 'sans,11'
set output 'docs/results/calibration_onion/calibration.png'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.106, AUROC 1.000)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.106, AUROC 1.000)'
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
set output 'docs/results/calibration_onion/calibration.svg'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.106, AUROC 1.000)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.106, AUROC 1.000)'
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
