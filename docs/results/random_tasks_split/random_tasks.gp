# Written by hbirl; run `gnuplot docs/results/random_tasks_split/random_tasks.gp` to redraw.
$optimal << EOD
"all" 30.3333 26.7897 34.1271 28.1667 24.7152 31.896
"|E| = 0" 37.037 27.3317 47.9163 34.5679 25.1226 45.4106
"|E| 1-3" 32.3671 26.3648 39.012 27.0531 21.4604 33.4821
"|E| 4-7" 27.2436 22.6026 32.4382 27.2436 22.6026 32.4382
"occluded < 10%" 29.6296 23.5779 36.4929 26.9841 21.161 33.7242
"occluded 10-20%" 38.4977 32.2217 45.1811 30.9859 25.1586 37.487
"occluded 20-30%" 22.2222 16.9912 28.5106 26.2626 20.6267 32.8021
"informativeness < 0.53" 25.3086 19.2388 32.5224 24.0741 18.1401 31.2091
"informativeness 0.53-0.77" 29.3333 23.7712 35.5893 26.6667 21.3155 32.8012
"informativeness > 0.77" 35.2113 29.1106 41.8359 32.8638 26.9081 39.4267
"plausible eta" 28.3688 23.4256 33.8934 28.3688 23.4256 33.8934
"uniform eta" 32.0755 27.1854 37.3934 27.9874 23.3384 33.1619
"grid" 31.4286 26.5518 36.7528 30.4762 25.6534 35.7694
"graph" 29.1228 24.1536 34.6473 25.614 20.894 30.9827
"with a trap" 26.7717 22.5738 31.4333 22.8346 18.9032 27.3084
EOD
$near << EOD
"all" 67.8333 63.9924 71.4473 61.5 57.5451 65.3086
"|E| = 0" 81.4815 71.6684 88.4437 70.3704 59.688 79.208
"|E| 1-3" 64.7343 58.0109 70.9207 63.285 56.5321 69.5539
"|E| 4-7" 66.3462 60.9323 71.3623 58.0128 52.4715 63.3592
"occluded < 10%" 78.836 72.4679 84.0552 67.1958 60.2179 73.4886
"occluded 10-20%" 63.8498 57.2051 70.0037 60.5634 53.8688 66.8837
"occluded 20-30%" 61.6162 54.6823 68.1078 57.0707 50.1063 63.766
"informativeness < 0.53" 53.0864 45.4193 60.6105 48.7654 41.1865 56.4015
"informativeness 0.53-0.77" 69.3333 63.0257 74.9919 63.1111 56.6357 69.1464
"informativeness > 0.77" 77.4648 71.3959 82.5606 69.4836 62.9998 75.2771
"plausible eta" 63.8298 58.0706 69.2173 59.2199 53.3976 64.7943
"uniform eta" 71.3836 66.184 76.0728 63.522 58.0991 68.6221
"grid" 66.3492 60.962 71.3425 67.3016 61.9398 72.2465
"graph" 69.4737 63.8975 74.5319 55.0877 49.2834 60.7567
"with a trap" 60.6299 55.6414 65.4062 54.8556 49.8351 59.7793
EOD
set style data histograms
set style histogram errorbars gap 2 lw 1
set style fill solid 0.85 border -1
set boxwidth 0.9
set xtics rotate by -30 left
set grid ytics
set key outside right top
set yrange [0:105]
set ylabel '% of runs'
set bmargin 7
set terminal pngcairo size 1400,1100 noenhanced font 'sans,11'
set output 'docs/results/random_tasks_split/random_tasks.png'
set multiplot layout 2,1
set title 'Random tasks: runs whose learned policy is optimal (ILE 0; 95% Wilson interval)'
plot $optimal using 2:3:4:xtic(1) title 'oracle_sensor' lc rgb '#1b9e77', \
     $optimal using 5:6:7 title 'posterior' lc rgb '#d95f02'
set title 'Runs within 5% of the optimal value (ILE <= 0.05 ||V*||_1)'
plot $near using 2:3:4:xtic(1) title 'oracle_sensor' lc rgb '#1b9e77', \
     $near using 5:6:7 title 'posterior' lc rgb '#d95f02'
unset multiplot
set terminal svg size 1400,1100 noenhanced font 'sans,11' background rgb 'white'
set output 'docs/results/random_tasks_split/random_tasks.svg'
set multiplot layout 2,1
set title 'Random tasks: runs whose learned policy is optimal (ILE 0; 95% Wilson interval)'
plot $optimal using 2:3:4:xtic(1) title 'oracle_sensor' lc rgb '#1b9e77', \
     $optimal using 5:6:7 title 'posterior' lc rgb '#d95f02'
set title 'Runs within 5% of the optimal value (ILE <= 0.05 ||V*||_1)'
plot $near using 2:3:4:xtic(1) title 'oracle_sensor' lc rgb '#1b9e77', \
     $near using 5:6:7 title 'posterior' lc rgb '#d95f02'
unset multiplot
unset output
