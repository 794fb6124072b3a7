# Written by hbirl; run `gnuplot docs/results/calibration/calibration.gp` to redraw.
$d0 << EOD
0.0166362 0.184211 0.0922177 0.334189 0.05 38
0.147926 0.25 0.101821 0.494983 0.15 16
0.253916 0 1.38778e-17 0.215311 0.25 14
0.334285 0.25 0.111862 0.468701 0.35 20
0.451818 0.157895 0.0552047 0.375655 0.45 19
0.559152 0.428571 0.2447 0.634534 0.55 21
0.644745 0.45 0.258198 0.657915 0.65 20
0.752245 0.375 0.24223 0.529676 0.75 40
0.852332 0.611111 0.477883 0.729581 0.85 54
0.98574 0.810056 0.766214 0.847315 0.95 358
EOD
$d1 << EOD
0.021004 0.333333 0.0967714 0.700007 0.05 6
0.129897 1 0.34238 1 0.15 2
0.231167 0.2 0.0362241 0.624465 0.25 5
0.353276 0.333333 0.0967714 0.700007 0.35 6
0.548019 0.6 0.230724 0.882379 0.55 5
0.637128 1 0.64567 1 0.65 7
0.748188 0.916667 0.64612 0.985135 0.75 12
0.857407 0.962963 0.817165 0.993432 0.85 27
0.98829 0.986792 0.972991 0.993588 0.95 530
EOD
set terminal pngcairo size 1000,1100 noenhanced font 'sans,11'
set output 'docs/results/calibration/calibration.png'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.194, AUROC 0.819)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.021, AUROC 0.912)'
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
set output 'docs/results/calibration/calibration.svg'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.194, AUROC 0.819)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.021, AUROC 0.912)'
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
