# Written by hbirl; run `gnuplot docs/results/calibration/calibration.gp` to redraw.
$d0 << EOD
0.0284938 0.227273 0.128419 0.369924 0.05 44
0.156149 0.0526316 0.00935199 0.246387 0.15 19
0.251609 0.285714 0.138139 0.499564 0.25 21
0.351991 0.3 0.166647 0.478758 0.35 30
0.459853 0.27451 0.171143 0.409467 0.45 51
0.542412 0.442308 0.315951 0.576602 0.55 52
0.656584 0.589744 0.434186 0.729207 0.65 39
0.745555 0.566038 0.432654 0.690496 0.75 53
0.853528 0.745763 0.622039 0.83944 0.85 59
0.977619 0.926724 0.885797 0.95375 0.95 232
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.097, AUROC 0.849)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.021, AUROC 0.912)'
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
plot x title 'calibrated' lc rgb '#888888' dt 2, $d0 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#d95f02' title 'from observations (ECE 0.097, AUROC 0.849)', $d1 using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '#1b9e77' title 'from truth (ECE 0.021, AUROC 0.912)'
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
