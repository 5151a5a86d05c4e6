// uart_rx: 8N1 UART receiver with a valid/ready byte output and error counters.
//
// Assumptions: rx_i is asynchronous (a two-flip-flop synchronizer is inside); CLK_HZ / BAUD >= 4;
// the sender's rate is within +-2 % of BAUD.
// Guarantees: a byte is offered on data_o/valid_o until taken with ready_i; a byte whose stop bit
// is low is dropped and counted in framing_errors_o; a byte that arrives while the previous one is
// still not taken is dropped and counted in overruns_o (the older byte is kept). Counters saturate; their
// widths are those of the LINK_ERRORS fields, the defaults the board's clock and UART rate (both from
// common/regmap.json).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module uart_rx #(
    parameter integer CLK_HZ = `OMNILOC_BOARD_CLOCK_HZ,
    parameter integer BAUD   = `OMNILOC_UART_BAUD
) (
    input  wire                                   clk_i,
    input  wire                                   rst_i,
    input  wire                                   rx_i,
    output wire [7:0]                             data_o,
    output wire                                   valid_o,
    input  wire                                   ready_i,
    output wire [`OMNILOC_LINK_ERRORS_FRAMING_W-1:0] framing_errors_o,
    output wire [`OMNILOC_LINK_ERRORS_OVERRUN_W-1:0] overruns_o
);

localparam integer FE_W = `OMNILOC_LINK_ERRORS_FRAMING_W;
localparam integer OE_W = `OMNILOC_LINK_ERRORS_OVERRUN_W;

localparam integer CLKS_PER_BIT = (CLK_HZ + BAUD / 2) / BAUD;
localparam integer DIV_W = $clog2(CLKS_PER_BIT + 1);
localparam integer BIT_LAST_I = CLKS_PER_BIT - 1;
localparam [DIV_W-1:0] BIT_LAST = BIT_LAST_I[DIV_W-1:0];
localparam integer HALF_LAST_I = CLKS_PER_BIT / 2 - 1;
localparam [DIV_W-1:0] HALF_LAST = HALF_LAST_I[DIV_W-1:0];

localparam [1:0] S_IDLE = 2'd0, S_START = 2'd1, S_DATA = 2'd2, S_STOP = 2'd3;

reg [1:0]       sync_q;
reg             prev_q;      // line level one cycle earlier: a start bit is a falling edge
reg [1:0]       state_q;
reg [DIV_W-1:0] div_q;
reg [2:0]       bit_q;
reg [7:0]       shift_q;
reg [7:0]       data_q;
reg             valid_q;
reg [FE_W-1:0]  framing_q;
reg [OE_W-1:0]  overrun_q;

wire rx_s = sync_q[1];

assign data_o           = data_q;
assign valid_o          = valid_q;
assign framing_errors_o = framing_q;
assign overruns_o       = overrun_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        sync_q    <= 2'b11;
        prev_q    <= 1'b1;
        state_q   <= S_IDLE;
        div_q     <= {DIV_W{1'b0}};
        bit_q     <= 3'd0;
        shift_q   <= 8'd0;
        data_q    <= 8'd0;
        valid_q   <= 1'b0;
        framing_q <= {FE_W{1'b0}};
        overrun_q <= {OE_W{1'b0}};
    end else begin
        sync_q <= {sync_q[0], rx_i};
        prev_q <= rx_s;
        if (valid_q && ready_i) valid_q <= 1'b0;
        case (state_q)
            // After a framing error the line may still be low: only a falling edge starts a byte.
            S_IDLE: if (prev_q && !rx_s) begin
                state_q <= S_START;
                div_q   <= HALF_LAST;   // to the middle of the start bit
            end
            S_START: if (div_q != {DIV_W{1'b0}}) begin
                div_q <= div_q - 1'b1;
            end else if (rx_s) begin
                state_q <= S_IDLE;                          // a glitch, not a start bit
            end else begin
                state_q <= S_DATA;
                bit_q   <= 3'd0;
                div_q   <= BIT_LAST;
            end
            S_DATA: if (div_q != {DIV_W{1'b0}}) begin
                div_q <= div_q - 1'b1;
            end else begin
                shift_q <= {rx_s, shift_q[7:1]};
                div_q   <= BIT_LAST;
                bit_q   <= bit_q + 1'b1;
                if (bit_q == 3'd7) state_q <= S_STOP;
            end
            default: if (div_q != {DIV_W{1'b0}}) begin  // S_STOP
                div_q <= div_q - 1'b1;
            end else begin
                state_q <= S_IDLE;
                if (!rx_s) begin
                    if (framing_q != {FE_W{1'b1}}) framing_q <= framing_q + 1'b1;
                end else if (valid_q && !ready_i) begin
                    if (overrun_q != {OE_W{1'b1}}) overrun_q <= overrun_q + 1'b1;
                end else begin
                    data_q  <= shift_q;
                    valid_q <= 1'b1;
                end
            end
        endcase
    end
end

`ifdef FORMAL
reg f_past_valid = 1'b0;
always @(posedge clk_i) f_past_valid <= 1'b1;
always @(*) if (!f_past_valid) assume(rst_i);   // start from reset
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i)) begin
        // Counters never go backwards and move by at most one.
        assert(framing_q == $past(framing_q) || framing_q == $past(framing_q) + 1'b1);
        assert(overrun_q == $past(overrun_q) || overrun_q == $past(overrun_q) + 1'b1);
        // An offered byte is held until taken.
        if ($past(valid_q) && !$past(ready_i)) assert(valid_q && data_q == $past(data_q));
        assert(div_q <= BIT_LAST);
    end
end

// Each property reachable: a byte delivered, a framing error counted.
always @(posedge clk_i) begin
    if (f_past_valid && !$past(rst_i) && !rst_i) begin
        cover (valid_q && !$past(valid_q));
        cover (framing_q == {{(FE_W-1){1'b0}}, 1'b1});
    end
end
`endif

endmodule

`default_nettype wire
